#!/usr/bin/env python3
"""numpy + h5py doing what `lidarsim simulate --method aggregate` does, one thread.

Reads a raw file written by lidarsim (only its layout and means: `counts`' shape, dtype
and chunk shape, `expected_counts` and `n_shots`), then, chunk-aligned block by block:
draws `Generator.poisson` with the file's means (`expected_counts` x `n_shots`, per
profile where the scene changes) and writes the counts with h5py into a new file with
the same chunk shape, shuffle and gzip level 1. With `--truth` it also writes every
(profile, channel, bin) float64 variable of the lidarsim file (a changing scene's truth)
the same way (read from the lidarsim file, untimed). Drawing and writing are timed
apart, writing including the file's close (where HDF5 compresses the chunks left in its
chunk cache); the best and median of `--repeat` runs are printed.

    python3 benches/numpy_h5py_write.py LIDARSIM.h5 OUT.h5 [--truth] [--repeat 3]

Needs numpy and h5py. h5py's HDF5 filters run in the calling thread: one thread.
"""
import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import h5py  # noqa: E402
import numpy as np  # noqa: E402


def run(src, out, truth, rng):
    counts = src["counts"]
    shape, dtype, chunks = counts.shape, counts.dtype, counts.chunks
    expected = src["expected_counts"][()]
    n_shots = src["n_shots"][()].astype(np.float64)
    per_profile = expected.ndim == 3
    extra = []
    if truth:
        extra = [
            k
            for k, v in src.items()
            if k != "counts" and v.ndim == 3 and v.dtype == np.float64 and v.chunks
        ]
    draw = write = 0.0
    f = h5py.File(out, "w")
    ds = f.create_dataset(
        "counts", shape=shape, dtype=dtype, chunks=chunks, shuffle=True,
        compression="gzip", compression_opts=1,
    )
    others = {
        k: f.create_dataset(
            k, shape=src[k].shape, dtype=np.float64, chunks=src[k].chunks,
            shuffle=True, compression="gzip", compression_opts=1,
        )
        for k in extra
    }
    step = chunks[0]
    for a in range(0, shape[0], step):
        b = min(a + step, shape[0])
        rows = {k: src[k][a:b] for k in extra}  # untimed: the model's output
        t0 = time.perf_counter()
        base = expected[a:b] if per_profile else expected[None, :, :]
        lam = base * n_shots[a:b, None, None]
        x = rng.poisson(lam)
        t1 = time.perf_counter()
        ds[a:b] = x.astype(dtype)
        for k, d in others.items():
            d[a:b] = rows[k]
        t2 = time.perf_counter()
        draw += t1 - t0
        write += t2 - t1
    t0 = time.perf_counter()
    f.close()  # HDF5 compresses the chunks still in its chunk cache here
    write += time.perf_counter() - t0
    return draw, write, os.path.getsize(out), extra


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("lidarsim_file")
    ap.add_argument("out")
    ap.add_argument("--truth", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    src = h5py.File(args.lidarsim_file, "r")
    c = src["counts"]
    print(
        f"numpy {np.__version__}, h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version}): "
        f"counts {c.shape} {c.dtype}, chunks {c.chunks}, shuffle + gzip 1"
    )
    rng = np.random.default_rng(1)
    results = [run(src, args.out, args.truth, rng) for _ in range(args.repeat)]
    draws = [r[0] for r in results]
    writes = [r[1] for r in results]
    totals = [r[0] + r[1] for r in results]
    if results[0][3]:
        print(f"also written: {', '.join(results[0][3])}")
    med = statistics.median
    print(
        f"draw {med(draws):.3f} s (best {min(draws):.3f}), write {med(writes):.3f} s "
        f"(best {min(writes):.3f}), total {med(totals):.3f} s (best {min(totals):.3f}); "
        f"medians of {args.repeat}; file {results[-1][2]} bytes"
    )


if __name__ == "__main__":
    main()
