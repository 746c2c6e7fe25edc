#!/usr/bin/env python3
"""numpy Generator.poisson, ns per draw at the means of validation/sampler_costs.rs.

For each mean, 1000 bins all at that mean, `shots` x 1000 draws per call (about 2e6),
best of `--repeat` calls, one thread. Prints `mean ns_per_draw Mdraws_per_s`, one line
per mean, the same means and layout as `cargo run --release --example sampler_costs`.

    python3 benches/numpy_poisson_means.py [--repeat 15]
"""
import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

MEANS = [1e-3, 0.01, 0.05, 0.1, 0.25, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0, 1e3, 1e4, 1e5, 1e6]
BINS = 1000


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    print(f"numpy {np.__version__} Generator(PCG64).poisson, {BINS} bins, best of {args.repeat}")
    print(f"{'mean':>8} {'ns/draw':>10} {'M/s':>10}")
    for m in MEANS:
        lam = np.full(BINS, m)
        shots = 2000
        best = float("inf")
        for _ in range(args.repeat):
            t = time.perf_counter()
            rng.poisson(lam, size=(shots, BINS))
            best = min(best, time.perf_counter() - t)
        ns = best * 1e9 / (shots * BINS)
        print(f"{m:>8.0e} {ns:10.2f} {1e3 / ns:10.1f}")


if __name__ == "__main__":
    main()
