#!/usr/bin/env python3
"""Issue 11's side-by-side throughput checks, one thread each unless said, in one run.

Builds lidarsim (release), then measures and prints, with the ratios the issue judges:

1. CALIOP-like aggregate (configs/instruments/caliop_532.toml, 20,000 profiles of 15
   shots): the whole `simulate` run and its drawing against numpy drawing the same means
   plus h5py writing them with the same chunking and compression
   (benches/numpy_h5py_write.py); also with `--set acquisition.top_altitude_km=40`, the
   1,353-bin window the issue names.
2. Paper scenario 1 with 10,000-shot profiles: `aggregate` against `shot` per profile,
   whole runs with their files (20 shot profiles, 20,000 aggregate profiles).
3. The shot path on paper scenario 1 at 1 J (night) against numpy's Generator.poisson on
   the same per-shot means (drawing rates, as benches/side_by_side.sh).
4. Two threads against one on whole `simulate` runs (the orbit at shot level and the
   CALIOP-like aggregate run), and the peak memory of each run.

Every lidarsim figure is the median of `--repeat` runs (timings move by ±10-20 % with
the load of a shared machine). Needs numpy and h5py.

    python3 benches/throughput.py [--repeat 3]
"""
import argparse
import csv
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "lidarsim")
CALIOP = os.path.join(ROOT, "configs", "instruments", "caliop_532.toml")
ORBIT = os.path.join(ROOT, "configs", "instruments", "caliop_orbit.toml")
S1 = os.path.join(ROOT, "configs", "paper", "scenario1.toml")


def simulate(cfg, out, *args):
    """One `simulate` run: (whole run s, drawing s, peak memory kB) from its summary."""
    cmd = ["/usr/bin/time", "-f", "peak %M", BIN, "simulate", cfg, "-o", out, *args]
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    text = p.stdout + p.stderr
    whole = float(re.search(r"([0-9.]+) s in all", text).group(1))
    drawing = float(re.search(r"of which drawing ([0-9.]+) s", text).group(1))
    peak = int(re.search(r"peak (\d+)", text).group(1))
    return whole, drawing, peak


def median_runs(repeat, cfg, out, *args):
    runs = [simulate(cfg, out, *args) for _ in range(repeat)]
    return tuple(statistics.median(r[i] for r in runs) for i in range(3))


def numpy_h5py(src, out, repeat):
    """benches/numpy_h5py_write.py: median (draw s, write s)."""
    p = subprocess.run(
        [sys.executable, os.path.join(ROOT, "benches", "numpy_h5py_write.py"), src, out,
         "--repeat", str(repeat)],
        capture_output=True, text=True, check=True,
    )
    m = re.search(r"draw ([0-9.]+) s \(best [0-9.]+\), write ([0-9.]+) s", p.stdout)
    if not m:
        sys.exit(f"cannot read numpy_h5py_write.py's output:\n{p.stdout}")
    return float(m.group(1)), float(m.group(2))


def numpy_shot_rate(cfg, sets):
    """numpy Generator.poisson shot-bins/s on the per-shot means of `expect --csv`."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "lambda.csv")
        subprocess.run([BIN, "expect", cfg, *sets, "--csv", path], check=True,
                       capture_output=True)
        rows = list(csv.DictReader(open(path)))
    lam = np.array([float(r["signal"]) + float(r["background"]) + float(r["dark"])
                    for r in rows])
    rng = np.random.default_rng(1)
    best = 0.0
    for _ in range(10):
        t = time.perf_counter()
        rng.poisson(lam, size=(1000, lam.size)).sum(axis=0)
        best = max(best, 1000 * lam.size / (time.perf_counter() - t))
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    r = ap.parse_args().repeat
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    one = ["--threads", "1"]
    with tempfile.TemporaryDirectory() as tmp:
        f = lambda name: os.path.join(tmp, name)  # noqa: E731
        print("1. CALIOP-like aggregate, 20,000 profiles, one thread")
        for label, extra in [("3,358 bins (100 km)", []),
                             ("1,353 bins (40 km)", ["--set", "acquisition.top_altitude_km=40"])]:
            whole, drawing, peak = median_runs(
                r, CALIOP, f("c.h5"), "--method", "aggregate", "--profiles", "20000", *one, *extra)
            draw_np, write_np = numpy_h5py(f("c.h5"), f("np.h5"), r)
            print(f"   {label}: lidarsim {whole:.3f} s (drawing {drawing:.3f} s, {peak // 1024} MB); "
                  f"numpy {draw_np:.3f} s + h5py {write_np:.3f} s")
            print(f"     whole run {(draw_np + write_np) / whole:.1f}x numpy + h5py (goal 3x); "
                  f"drawing {draw_np / drawing:.1f}x numpy's (goal 5x)")
        print("2. Scenario 1, 10,000-shot profiles: aggregate against shot, whole runs, one thread")
        s1 = ["--set", "acquisition.accumulation_time_s=1000"]
        shot, _, _ = median_runs(r, S1, f("s.h5"), "--method", "shot", "--profiles", "20", *one, *s1)
        agg, agg_draw, _ = median_runs(
            r, S1, f("a.h5"), "--method", "aggregate", "--profiles", "20000", *one, *s1)
        per_shot, per_agg = shot / 20, agg / 20000
        per_draw = agg_draw / 20000
        print(f"   shot {per_shot * 1e3:.2f} ms per profile, aggregate {per_agg * 1e6:.2f} us "
              f"(drawing {per_draw * 1e6:.2f} us): {per_shot / per_agg:.0f}x (goal 1000x); "
              f"drawing alone {per_shot / per_draw:.0f}x")
        print("3. Shot path, scenario 1 at 1 J, night, 1,000-shot profiles, one thread")
        s1_100 = ["--set", "acquisition.accumulation_time_s=100"]
        _, drawing, _ = median_runs(r, S1, f("s.h5"), "--method", "shot", "--profiles", "50", *one, *s1_100)
        ours = 50 * 1000 * 334 / drawing
        theirs = numpy_shot_rate(S1, s1_100)
        print(f"   lidarsim {ours:.3g} shot-bins/s, numpy {theirs:.3g}: {ours / theirs:.1f}x (goal 10x)")
        print("4. Two threads against one, whole runs")
        for label, cfg, args in [
            ("orbit, shot, 7,960 profiles", ORBIT, ["--method", "shot", "--profiles", "7960",
                                                    "--set", "acquisition.top_altitude_km=40"]),
            ("CALIOP-like, aggregate, 20,000 profiles", CALIOP,
             ["--method", "aggregate", "--profiles", "20000"]),
        ]:
            t1, _, m1 = median_runs(r, cfg, f("t.h5"), *args, "--threads", "1")
            t2, _, m2 = median_runs(r, cfg, f("t.h5"), *args, "--threads", "2")
            print(f"   {label}: {t1:.3f} s / {t2:.3f} s = {t1 / t2:.2f}x (goal 1.7x); "
                  f"peak memory {m1 // 1024} / {m2 // 1024} MB")


if __name__ == "__main__":
    main()
