#!/usr/bin/env python3
"""Writes configs/atmospheres/curtain_example.h5, the example curtain of docs/scenes.md:
40 columns of 5 km (200 km) x 30 altitude cells of 0.5 km (0-15 km), at 532 nm: a smoke
plume rising from 1-3 km to 4-6 km along the track (extinction 0.2 km-1, lidar ratio
70 sr, depolarization 0.05, Angstrom exponent 1.4) and a cirrus 9-11 km over the middle
third (0.3 km-1, 25 sr, 0.4). Needs numpy and h5py.

    python3 tools/make_curtain_example.py [OUT.h5]
"""
import sys

import h5py
import numpy as np

out = sys.argv[1] if len(sys.argv) > 1 else "configs/atmospheres/curtain_example.h5"
x = np.arange(40) * 5.0
z = 0.25 + np.arange(30) * 0.5
ext_a = np.zeros((x.size, z.size))
ext_c = np.zeros((x.size, z.size))
for i in range(x.size):
    base = 1.0 + 3.0 * i / (x.size - 1)
    ext_a[i, (z > base) & (z < base + 2.0)] = 0.2
    if x.size // 3 <= i < 2 * x.size // 3:
        ext_c[i, (z > 9.0) & (z < 11.0)] = 0.3
with h5py.File(out, "w", track_order=True) as f:
    f.attrs["wavelength_nm"] = 532.0
    f.attrs["title"] = "lidarsim example curtain: a rising smoke plume and a cirrus"
    f["along_track_km"] = x
    f["altitude_km"] = z
    d = f.create_dataset("extinction_aerosol", data=ext_a)
    d.attrs["angstrom_exponent"] = 1.4
    f["lidar_ratio_aerosol"] = np.full(ext_a.shape, 70.0)
    f["depolarization_aerosol"] = np.full(ext_a.shape, 0.05)
    f["extinction_cloud"] = ext_c
    f["lidar_ratio_cloud"] = np.full(ext_c.shape, 25.0)
    f["depolarization_cloud"] = np.full(ext_c.shape, 0.4)
print(f"wrote {out}")
