#!/usr/bin/env bash
# Scale criterion of issue 39: a whole day of a CALIOP-like instrument (1.74e6 shots,
# 15-shot profiles, a new column every profile) through global ERA5-like fields at
# 0.25° with the complete truth, on the machine's cores; goal ≤ 15 min on 2 cores.
# Makes the fields once (target/fields/era5_like_global.nc, ~553 MB, ~1 min CPU), runs
# `lidarsim simulate benches/fields_whole_day.toml` under /usr/bin/time (wall time,
# peak RSS) and prints the output's size. PROFILES=N runs the first N profiles only
# (116000 = the whole day) and extrapolates the wall time linearly to the day.
#   PROFILES=5800 THREADS=2 bash benches/fields_whole_day.sh
set -euo pipefail
cd "$(dirname "$0")/.."
profiles=${PROFILES:-116000}
threads=${THREADS:-2}
py=${PYTHON:-/tmp/venv/bin/python}
fields=target/fields/era5_like_global.nc
if [ ! -s "$fields" ]; then
  "$py" tools/make_model_fields.py --global 0.25 --hours 0,6,12,18,24 --levels 37 target/fields
fi
cargo build --release --quiet
out=${OUT:-target/fields/whole_day.h5}
rm -f "$out"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/time -f 'wall %e s, user %U s, sys %S s, peak RSS %M kB' \
  target/release/lidarsim simulate benches/fields_whole_day.toml -o "$out" \
  --threads "$threads" --profiles "$profiles" 2>&1 | tail -n 12 | tee target/fields/last_run.log
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "output: $(stat -c %s "$out") bytes ($out), fields: $(stat -c %s "$fields") bytes"
wall=$(sed -n 's/^wall \([0-9.]*\) s.*/\1/p' target/fields/last_run.log)
echo "extrapolated to 116000 profiles: $(echo "$wall * 116000 / $profiles / 60" | bc -l | cut -c1-6) min (goal 15)"
