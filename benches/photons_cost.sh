#!/usr/bin/env bash
# Cost of writing time-tagged events (`simulate --photons`) against the same shot-level
# run without them, at ~1 recorded event per shot-bin (validation/reports/photons_cost.md).
# Usage: benches/photons_cost.sh [THREADS]   (after `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
L=target/release/lidarsim
T=${1:-1}
C=configs/instruments/icesat2_like.toml
S=(--set instrument.dark_count_rate_hz=5e7 --set instrument.detector.pixels=1
   --set instrument.detector.dead_time_s=0)
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
for i in 1 2; do
  "$L" simulate "$C" -o "$D/a.h5" --profiles 4 "${S[@]}" --threads "$T" 2>&1 | grep Wrote
  rm -f "$D/a.h5"
  "$L" simulate "$C" -o "$D/b.h5" --profiles 4 "${S[@]}" --threads "$T" --photons "$D/p.h5" 2>&1 | grep Wrote
  ls -l "$D/p.h5"
  rm -f "$D/b.h5" "$D/p.h5"
done
