#!/usr/bin/env python3
"""Dumps up to 16 MB of each (profile, channel, bin) variable of lidarsim raw files as
raw native bytes, named LABEL_VAR_ELEMBYTES_ROWELEMS.bin, for the compressor
comparison (src/main.rs).

    python3 dump.py FILE.h5 [FILE.h5 ...] --out DIR
"""
import argparse
import os

import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("files", nargs="+")
ap.add_argument("--out", required=True)
args = ap.parse_args()
os.makedirs(args.out, exist_ok=True)
for fn in args.files:
    label = os.path.splitext(os.path.basename(fn))[0].replace("_", "-")
    with h5py.File(fn, "r") as f:
        for name, d in f.items():
            if not isinstance(d, h5py.Dataset) or d.ndim != 3 or not d.chunks:
                continue
            row = d.shape[1] * d.shape[2]
            rows = max(1, (16 << 20) // (row * d.dtype.itemsize))
            a = np.ascontiguousarray(d[:rows])
            out = f"{args.out}/{label}_{name.replace('_', '-')}_{d.dtype.itemsize}_{row}.bin"
            a.tofile(out)
            print(out, a.shape, a.dtype)
