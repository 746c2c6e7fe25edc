#!/usr/bin/env bash
# Cost of the detector's dead time: the same `simulate --method shot` run with and
# without `instrument.detector.dead_time_s = 3.5e-9`, one thread, paper scenario 1 at
# night at several pulse energies (sparse to dense counts). Prints the drawing time of
# each and their ratio.
#   bash benches/dead_time_side_by_side.sh [PROFILES]   (default 20000)
set -euo pipefail
cd "$(dirname "$0")/.."
profiles=${1:-20000}
cargo build --release --quiet
bin=target/release/lidarsim
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
drawing() {
  local n=$1; shift
  "$bin" simulate configs/paper/scenario1.toml -o "$out/x.h5" --method shot --threads 1 \
    --profiles "$n" "$@" 2>&1 | sed -n 's/.*of which drawing \([0-9.]*\) s.*/\1/p'
}
printf '%-12s %9s %14s %14s %8s\n' "E0 (J)" "profiles" "no dead time" "dead time" "ratio"
for e in 0.0001 0.001 0.01 1; do
  n=$profiles; [ "$e" = 1 ] && n=$((profiles / 100))
  a=$(drawing "$n" --set instrument.pulse_energy_j=$e)
  b=$(drawing "$n" --set instrument.pulse_energy_j=$e --set instrument.detector.dead_time_s=3.5e-9)
  printf '%-12s %9s %12s s %12s s %8.1f\n' "$e" "$n" "$a" "$b" "$(echo "$b / $a" | bc -l)"
done
