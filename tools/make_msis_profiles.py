#!/usr/bin/env python3
"""Molecular profile files from NRLMSIS 2.1 for the seed paper's region and seasons.

Fochesatto et al. (2004) took their molecules from the MSIS-E-90 model at 1 km vertical
resolution, for a lidar studying the southern South American atmosphere. This script
makes the stand-in lidarsim ships: NRLMSIS 2.1 (Emmert et al. 2021, Earth Space Sci. 8,
e2020EA001321 — the successor of MSIS-E-90 and NRLMSISE-00) through the published
`pymsis` package (PyPI; `pip install pymsis numpy`), at the paper authors' station,
CEILAP, Villa Martelli, Buenos Aires (34.55 S, 58.50 W), at local midnight in the middle
of austral summer (15 January) and winter (15 July) of 2002, the paper's year.

Output: configs/atmospheres/nrlmsis21_buenos_aires_{january,july}.txt in the
`altitude_km pressure_hpa temperature_k` layout of a molecular profile file (the format
is described in docs/model.md and in the header of configs/atmospheres/us76_1km.txt),
0-86 km at 1 km steps. The pressure is p = N k_B T from MSIS's total number density N
(N2 + O2 + O + He + H + Ar + N) and its temperature T, so lidarsim's N = p/(k_B T) is
MSIS's own N.

Choices (ASSUMED, written into each file's header):
- F10.7 = F10.7A = 150 sfu and Ap = 4 (the model's quiet, moderate-activity inputs);
  below 86 km NRLMSIS hardly depends on them (N at 10 and 15 km changes by < 4e-6
  between F10.7 = 70 and 250, by ~1 % at 80 km).
- The profile ends at 86 km, the top of US76 (lidarsim's default), so the paper
  scenarios keep the same signal-free bins between 86 and 100 km for the background
  estimate; MSIS's N at 86 km is ~2e-5 of that at 10 km.

Run: python3 tools/make_msis_profiles.py [OUT_DIR]   (default configs/atmospheres)
"""

import os
import sys

import numpy as np
import pymsis

K_B = 1.380649e-23  # J/K, exact (SI 2019)
LAT_DEG, LON_DEG = -34.55, -58.50  # CEILAP, Villa Martelli, Buenos Aires
F107, F107A, AP = 150.0, 150.0, 4.0  # ASSUMED, see above
ALT_KM = np.arange(0.0, 87.0, 1.0)
# local midnight at 58.5 W is 03:54 UTC
SEASONS = {
    "january": ("2002-01-15T03:54", "austral summer"),
    "july": ("2002-07-15T03:54", "austral winter"),
}
SPECIES = [
    pymsis.Variable.N2,
    pymsis.Variable.O2,
    pymsis.Variable.O,
    pymsis.Variable.HE,
    pymsis.Variable.H,
    pymsis.Variable.AR,
    pymsis.Variable.N,
]


def profile(date):
    out = pymsis.calculate(
        np.array([np.datetime64(date)]),
        np.array([LON_DEG]),
        np.array([LAT_DEG]),
        ALT_KM,
        f107s=np.array([F107]),
        f107as=np.array([F107A]),
        aps=np.array([[AP] * 7]),
        version=2.1,
    )
    out = np.squeeze(out)  # (altitude, variable)
    n_total = np.nansum(out[:, [int(s) for s in SPECIES]], axis=1)
    t_k = out[:, int(pymsis.Variable.TEMPERATURE)]
    p_hpa = n_total * K_B * t_k / 100.0
    return p_hpa, t_k


def write(path, date, season, p_hpa, t_k):
    with open(path, "w") as f:
        f.write(
            f"# NRLMSIS 2.1 (Emmert et al. 2021, Earth Space Sci. 8, e2020EA001321) through pymsis {pymsis.__version__},\n"
            f"# made by tools/make_msis_profiles.py: the seed paper's molecules (it used MSIS-E-90 at 1 km).\n"
            f"# Site: CEILAP, Villa Martelli, Buenos Aires, 34.55 S 58.50 W; {date} UTC (local midnight, {season}).\n"
            f"# Inputs ASSUMED: F10.7 = F10.7A = {F107:g} sfu, Ap = {AP:g}. 0-86 km at 1 km (the top of US76).\n"
            "# p = N k_B T with N = MSIS's total number density (N2+O2+O+He+H+Ar+N), T its temperature.\n"
            "# Format: the header of configs/atmospheres/us76_1km.txt, docs/model.md.\n"
            "#\n"
            "altitude_km  pressure_hpa  temperature_k\n"
        )
        for z, p, t in zip(ALT_KM, p_hpa, t_k):
            f.write(f"{z:5.1f}  {p:13.6e}  {t:8.3f}\n")


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "configs/atmospheres"
    for name, (date, season) in SEASONS.items():
        p_hpa, t_k = profile(date)
        if not (np.all(np.isfinite(p_hpa)) and np.all(p_hpa > 0) and np.all(t_k > 0)):
            sys.exit(f"make_msis_profiles: NRLMSIS gave a non-positive value for {name}")
        path = os.path.join(out_dir, f"nrlmsis21_buenos_aires_{name}.txt")
        write(path, date, season, p_hpa, t_k)
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
