#!/usr/bin/env bash
# A whole CALIOP-like orbit at shot level (issue 9's speed criterion): lidarsim
# `simulate --method shot --threads 1` on configs/instruments/caliop_orbit.toml over
# 7,960 profiles of 15 shots (119,400 shots, one 98.7 min orbit, the scene changing
# along it: segments, broken cloud, day and night), against numpy's Generator.poisson
# drawing the same per-shot means (each profile's own, rebuilt from the file's compact
# truth as `lidarsim.per_profile` does: its columns' expected signal mixed by the
# profile's column weights, plus its sky background and the dark counts) shot by shot,
# one thread each, in one run. Prints the ratio for the drawing of the counts alone and
# for lidarsim's whole run (model, complete truth, file) and the file's size; then the
# same run with `--truth per-profile` (format 3's per-profile arrays too), its time and
# size. Also the peak memory of half and the whole orbit (flat: the run streams its
# profiles).
# With the 40 km window (1,354 bins) the measurements were made with (the config
# records from 100 km since issue 18). Needs python3 with numpy, h5py.
#   bash benches/orbit_side_by_side.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/lidarsim
cfg=configs/instruments/caliop_orbit.toml
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for n in 3980 7960; do
  echo "== lidarsim simulate --method shot --threads 1 --profiles $n"
  /usr/bin/time -f "peak memory %M kB" "$bin" simulate "$cfg" -o "$tmp/orbit.h5" \
    --method shot --threads 1 --profiles "$n" --set acquisition.top_altitude_km=40 2>&1 | grep -v "^lidarsim: warning" | tee "$tmp/summary"
  ls -l "$tmp/orbit.h5" | awk '{printf "file: %.1f MB\n", $5 / 1e6}'
done
echo "== lidarsim simulate --method shot --threads 1 --profiles 7960 --truth per-profile"
"$bin" simulate "$cfg" -o "$tmp/per_profile.h5" --method shot --threads 1 --profiles 7960 \
  --truth per-profile --set acquisition.top_altitude_km=40 2>&1 | grep -v "^lidarsim: warning"
ls -l "$tmp/per_profile.h5" | awk '{printf "file: %.1f MB\n", $5 / 1e6}'
rm -f "$tmp/per_profile.h5"
echo "== numpy Generator.poisson, the same per-shot means, shot by shot"
OMP_NUM_THREADS=1 python3 - "$tmp/orbit.h5" "$tmp/summary" <<'PY'
import re, sys, time
import h5py
import numpy as np
f = h5py.File(sys.argv[1])
# the compact truth: expected signal per column, background per (profile, channel)
sig = f["expected_signal"][:, 0, :]
bkg = f["expected_background"][:, 0]
dark = f["expected_dark"][0, :]
cols, weights = f["profile_column"][:], f["profile_column_weight"][:]
shots = int(f["n_shots"][0])
rng = np.random.default_rng(1)
draws, elapsed = 0, 0.0
for p in range(cols.shape[0]):
    mixed = np.zeros(sig.shape[1])
    for c, w in zip(cols[p], weights[p]):
        mixed = mixed + w * sig[max(c, 0)]
    lam = mixed + bkg[p] + dark
    t0 = time.perf_counter()
    x = rng.poisson(lam, size=(shots, lam.size)).sum(axis=0)
    elapsed += time.perf_counter() - t0
    draws += x.size * shots
print(f"numpy: {draws:.4g} draws in {elapsed:.3f} s ({draws / elapsed:.3g} draws/s)")
summary = open(sys.argv[2]).read()
whole = float(re.search(r"([0-9.]+) s in all", summary).group(1))
drawing = float(re.search(r"of which drawing ([0-9.]+) s", summary).group(1))
print(f"lidarsim / numpy: drawing the counts {elapsed / drawing:.1f}x faster, "
      f"the whole run (model, truth, file) {elapsed / whole:.1f}x faster")
PY
