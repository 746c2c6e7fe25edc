#!/usr/bin/env bash
# Issue 39: the cost of a model-field scene against the same scene written by hand, and
# its memory against the track's length. `fields_as_segments` writes the segments the
# fields become (the same columns, bit for bit the same counts) as a config; both are
# simulated, wall time and peak memory (GNU time's %M) taken; then the fields run at
# 60, 120 and 240 profiles. Report: validation/reports/fields_cost.md.
#   bash validation/fields_cost.sh [CONFIG] [PROFILES]
# Needs python3 with numpy and h5py (the .ci/run venv has them).
set -euo pipefail
cd "$(dirname "$0")/.."
cfg=${1:-configs/instruments/caliop_fields.toml}
profiles=${2:-200}
cargo build --release --quiet --bin lidarsim --example fields_as_segments
dir=$(mktemp -d)
bin=target/release/lidarsim
target/release/examples/fields_as_segments "$cfg" "$profiles" "$dir/segments.toml"
run() { # LABEL ARGS...: one timed run
  local label=$1
  shift
  /usr/bin/time -f "$label: %e s wall, %M kB peak" "$bin" simulate "$@" 2>&1 | grep "$label:"
}
for i in 1 2 3; do
  run "fields   ($profiles profiles, run $i)" "$cfg" -o "$dir/f.h5" --profiles "$profiles"
  run "segments ($profiles profiles, run $i)" "$dir/segments.toml" -o "$dir/s.h5"
done
python3 - "$dir" <<'P'
import sys, h5py, numpy as np
d = sys.argv[1]
a, b = h5py.File(d + "/f.h5"), h5py.File(d + "/s.h5")
same = np.array_equal(a["counts"][:], b["counts"][:]) and a["counts"].shape == b["counts"].shape
print("counts:", "identical" if same else "DIFFER", a["counts"].shape)
P
for p in 60 120 240; do
  run "fields ($p profiles)" "$cfg" -o "$dir/m.h5" --profiles "$p"
done
rm -rf "$dir"
