#!/usr/bin/env bash
# The raw-file writer in whole runs (issue 11, part 2), side by side in one run:
# `lidarsim simulate` on the orbit (shot, 7,960 profiles), the CALIOP-like config
# (aggregate, 20,000 profiles) and paper scenario 1 (2,000 profiles of 1000 s), with one
# and two threads, then numpy drawing the same means + h5py writing them with the same
# chunking, shuffle and gzip 1 (benches/numpy_h5py_write.py), one thread.
#   bash benches/writer_side_by_side.sh [REPEAT]        (default 5 runs each; medians)
# BIN=path/to/lidarsim measures another build (e.g. one from before the change).
# Needs python3 with numpy and h5py.
set -euo pipefail
cd "$(dirname "$0")/.."
repeat=${1:-5}
if [ -z "${BIN:-}" ]; then
  cargo build --release --quiet
  BIN=target/release/lidarsim
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export SOURCE_DATE_EPOCH=1700000000

median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }

run() { # name threads args...
  local name=$1 threads=$2
  shift 2
  local all=() draw=()
  for _ in $(seq "$repeat"); do
    local line
    line=$("$BIN" simulate "$@" -o "$tmp/$name.h5" --threads "$threads" 2>&1 | grep '^Wrote')
    all+=("$(sed -E 's/.* ([0-9.]+) s in all.*/\1/' <<<"$line")")
    draw+=("$(sed -E 's/.*drawing ([0-9.]+) s.*/\1/' <<<"$line")")
  done
  printf '%-9s %d thread(s): whole run %s s, drawing %s s (medians of %d: %s); file %s bytes\n' \
    "$name" "$threads" "$(printf '%s\n' "${all[@]}" | median)" \
    "$(printf '%s\n' "${draw[@]}" | median)" "$repeat" "${all[*]}" \
    "$(stat -c %s "$tmp/$name.h5")"
}

for threads in 1 2; do
  run orbit "$threads" configs/instruments/caliop_orbit.toml --method shot --profiles 7960 \
    --set acquisition.top_altitude_km=40
  run caliop "$threads" configs/instruments/caliop_532.toml --method aggregate --profiles 20000
  run scenario1 "$threads" configs/paper/scenario1.toml --profiles 2000 \
    --set acquisition.accumulation_time_s=1000
done
echo "== numpy + h5py, one thread, same means, chunks, shuffle and gzip 1"
for name in caliop scenario1; do
  echo "-- $name (counts)"
  python3 benches/numpy_h5py_write.py "$tmp/$name.h5" "$tmp/np.h5" --repeat "$repeat"
done
echo "-- orbit (counts and the five f64 truth variables)"
python3 benches/numpy_h5py_write.py "$tmp/orbit.h5" "$tmp/np.h5" --truth --repeat "$repeat"
