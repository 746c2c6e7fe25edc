#!/usr/bin/env bash
# lidarsim's shot path against numpy's Generator.poisson on the same λ per bin and the
# same shots × bins, one thread each, in one run (issue 3's speed criterion).
#   bash benches/side_by_side.sh [CONFIG] [--set KEY=VALUE ...]
# Default: paper scenario 1 at E0 = 0.1 mJ (every λ ≤ 0.07), 10 Hz × 1000 s profiles.
# Needs python3 with numpy.
set -euo pipefail
cd "$(dirname "$0")/.."
cfg=${1:-configs/paper/scenario1.toml}
shift || true
sets=("$@")
[ ${#sets[@]} -eq 0 ] && sets=(--set instrument.pulse_energy_j=1e-4 --set acquisition.accumulation_time_s=1000)
cargo build --release --quiet
bin=target/release/lidarsim
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
$bin expect "$cfg" "${sets[@]}" --csv "$tmp/lambda.csv"
echo "== lidarsim simulate --method shot --threads 1 (50 profiles)"
$bin simulate "$cfg" "${sets[@]}" -o "$tmp/out.h5" --method shot --threads 1 --profiles 50 2>&1
echo "== numpy Generator.poisson on the same λ per bin, same shots × bins"
OMP_NUM_THREADS=1 python3 - "$tmp/lambda.csv" "$bin" "$cfg" "${sets[@]}" <<'PY'
import csv, subprocess, sys, time
import numpy as np
rows = list(csv.DictReader(open(sys.argv[1])))
lam = np.array([float(r["signal"]) + float(r["background"]) + float(r["dark"]) for r in rows])
print(f"bins {lam.size}, max λ {lam.max():.3g}, Σλ per shot {lam.sum():.3g}")
rng = np.random.default_rng(1)
shots = 1000  # per call; the rate does not depend on it beyond a few hundred
best = 0.0
for _ in range(20):
    t = time.perf_counter()
    rng.poisson(lam, size=(shots, lam.size)).sum(axis=0)
    dt = time.perf_counter() - t
    best = max(best, shots * lam.size / dt)
print(f"numpy {np.__version__}: {best:.3e} shot-bins/s (best of 20 calls of {shots} shots)")
PY
