#!/usr/bin/env bash
# Cost of the detector's dead time on whole runs (issues 21 and 41): the same
# `simulate --method shot` run with and without `instrument.detector.dead_time_s =
# 3.5e-9`, one thread, paper scenario 1 (100 shots a profile), both models. Part 1: 1 J
# at night and by day (`background.radiance = 1.1e15`), PROFILES_1J profiles (default 20).
# Part 2: night at lower energies, PROFILES profiles (sparse counts). Prints the drawing
# rate of each (the run's own "of which drawing ... shot-bins/s" figure, four digits
# where the time is printed to the ms: wall time of one thread, so the shared machine's
# load shows; repeat and take the least) and the ratio of the drawing times.
#   bash benches/dead_time_side_by_side.sh [PROFILES] [PROFILES_1J]   (defaults 2000, 20)
set -euo pipefail
cd "$(dirname "$0")/.."
profiles=${1:-2000}
profiles_1j=${2:-20}
cargo build --release --quiet
bin=target/release/lidarsim
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
drawing() {
  local n=$1; shift
  "$bin" simulate configs/paper/scenario1.toml -o "$out/x.h5" --method shot --threads 1 \
    --profiles "$n" "$@" 2>&1 | sed -n 's/.*of which drawing [0-9.]* s (\([0-9.e+]*\) shot-bins.*/\1/p'
}
printf '%-10s %-6s %-16s %9s %22s %22s %8s\n' "E0 (J)" "sky" "model" "profiles" \
  "no dead time (bins/s)" "dead time (bins/s)" "ratio"
row() {
  local e=$1 sky=$2 model=$3 n=$4
  local bg=()
  [ "$sky" = day ] && bg=(--set background.radiance=1.1e15)
  a=$(drawing "$n" --set instrument.pulse_energy_j="$e" "${bg[@]}")
  b=$(drawing "$n" --set instrument.pulse_energy_j="$e" "${bg[@]}" \
    --set instrument.detector.dead_time_s=3.5e-9 \
    --set instrument.detector.dead_time_model="\"$model\"")
  printf '%-10s %-6s %-16s %9s %22s %22s %8.2f\n' "$e" "$sky" "$model" "$n" "$a" "$b" \
    "$(python3 -c "print($a / $b)")"
}
for sky in night day; do
  for model in nonparalyzable paralyzable; do
    row 1 "$sky" "$model" "$profiles_1j"
  done
done
for e in 0.0001 0.001 0.01; do
  for model in nonparalyzable paralyzable; do
    row "$e" night "$model" "$profiles"
  done
done
