#!/usr/bin/env python3
"""numpy Generator.poisson throughput in shot-bins per second, one thread.

Same grid and profile as benches/sampler.rs: 1000 bins, all bins at
lambda = 1e-4, 1e-2, 1, 10, and the low-energy profile
0.149 (1 + i/100)^-2 exp(-i/500) + 1e-3. Each call draws a (shots, bins)
array of independent Poisson counts (what one per-shot Monte Carlo step
needs), 1000 shots x 1000 bins; the best of `--repeat` calls is reported
(and the median), with and without the sum over shots that accumulates a
profile.

    python3 benches/numpy_poisson.py [--repeat 20]
"""
import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

BINS = 1000
SHOTS = 1000


def low_energy_profile():
    i = np.arange(BINS, dtype=float)
    return 0.149 * (1.0 + i / 100.0) ** -2 * np.exp(-i / 500.0) + 1e-3


def bench(rng, lam, repeat, accumulate):
    times = []
    acc = np.zeros(BINS, dtype=np.int64)
    for _ in range(repeat):
        t0 = time.perf_counter()
        x = rng.poisson(lam, size=(SHOTS, BINS))
        if accumulate:
            acc += x.sum(axis=0)
        times.append(time.perf_counter() - t0)
    times.sort()
    n = SHOTS * BINS
    return n / times[0], n / times[len(times) // 2]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    cases = [(f"lambda={l:g}", np.full(BINS, l)) for l in (1e-4, 1e-2, 1.0, 10.0)]
    cases.append(("low_energy", low_energy_profile()))
    print(f"numpy {np.__version__}, Generator(PCG64).poisson, {SHOTS} shots x {BINS} bins per call")
    print(f"{'case':<14} {'best Mshot-bins/s':>18} {'median':>10} {'best +sum':>10}")
    for name, lam in cases:
        best, med = bench(rng, lam, args.repeat, False)
        best_acc, _ = bench(rng, lam, args.repeat, True)
        print(f"{name:<14} {best / 1e6:18.1f} {med / 1e6:10.1f} {best_acc / 1e6:10.1f}")


if __name__ == "__main__":
    main()
