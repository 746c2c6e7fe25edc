#!/usr/bin/env bash
# Do two builds of lidarsim write the same bytes? For every shipped config (configs/),
# both binaries write `expect --csv`, a raw file (`simulate`, the config's method, and
# `--method shot` too) and its quicklook PNG, with SOURCE_DATE_EPOCH fixed; the script
# prints one line per output and exits 1 if any output differs (or one binary fails
# where the other does not).
#
# A refactor that claims "behaviour unchanged" (issue 37) runs this with the binary built
# before it and the one built after:
#
#   git worktree add /tmp/before <commit before>; (cd /tmp/before && cargo build --release)
#   cargo build --release
#   validation/same_outputs.sh /tmp/before/target/release/lidarsim target/release/lidarsim
#
# PROFILES (default 4) caps `--profiles` so the whole run takes a few minutes on 2 cores;
# an orbit's later segments are then not drawn, but every code path of its first
# profiles is. OUT (default a temporary directory, removed at the end) keeps the files.
set -uo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 OLD_LIDARSIM NEW_LIDARSIM" >&2
  exit 2
fi
old=$(realpath "$1") new=$(realpath "$2")
cd "$(dirname "$0")/.."
profiles=${PROFILES:-4}
keep=${OUT:-}
out=${OUT:-$(mktemp -d)}
mkdir -p "$out/old" "$out/new"
export SOURCE_DATE_EPOCH=1700000000
differ=0 compared=0

# mask FILE SIDE: a message with its output directory and its timings and rates masked
mask() {
  sed -E "s#$out/$2#@#g; s/[0-9.]+(e[-+]?[0-9]+)? (s|ms|µs|min|shot-bins\/s)\b/T/g" "$1"
}

# run NAME ARGS...: both binaries, output paths given as @/NAME.ext, then compare
run() {
  local name=$1
  shift
  local side bin rc_old rc_new
  for side in old new; do
    if [ $side = old ]; then bin=$old; else bin=$new; fi
    local args=("${@//@/$out/$side}")
    "$bin" "${args[@]}" >"$out/$side/$name.stdout" 2>"$out/$side/$name.stderr"
    echo $? >"$out/$side/$name.rc"
  done
  rc_old=$(cat "$out/old/$name.rc") rc_new=$(cat "$out/new/$name.rc")
  if [ "$rc_old" != "$rc_new" ]; then
    echo "DIFFER  $name: exit $rc_old before, $rc_new after"
    differ=$((differ + 1))
    return
  fi
  local f any=0
  for f in "$out/old/$name".*; do
    local base=${f##*/}
    case $base in *.stdout | *.rc) continue ;; esac
    any=1
    compared=$((compared + 1))
    if [ $base = "$name.stderr" ]; then
      # timings and rates differ from run to run; compare the rest
      if ! diff -q <(mask "$f" old) <(mask "$out/new/$base" new) >/dev/null; then
        echo "DIFFER  $base (messages)"
        differ=$((differ + 1))
      fi
    elif ! cmp -s "$f" "$out/new/$base"; then
      echo "DIFFER  $base"
      differ=$((differ + 1))
    else
      echo "same    $base ($(stat -c %s "$f") bytes, exit $rc_old)"
    fi
  done
  [ $any = 1 ] || echo "note    $name: no output (exit $rc_old)"
}

for config in $(find configs -name '*.toml' | sort); do
  name=$(basename "$config" .toml)
  run "$name-expect" expect "$config" --csv "@/$name-expect.csv"
  run "$name-raw" simulate "$config" --profiles "$profiles" -o "@/$name-raw.h5"
  run "$name-shot" simulate "$config" --profiles 2 --method shot -o "@/$name-shot.h5"
  if [ -f "$out/old/$name-raw.h5" ]; then
    run "$name-quicklook" quicklook "$out/old/$name-raw.h5" --png "@/$name-quicklook.png"
    run "$name-truth" quicklook "$out/old/$name-raw.h5" --truth --png "@/$name-truth.png"
  fi
done
echo "$compared outputs compared, $differ differ"
[ -n "$keep" ] || rm -rf "$out"
[ $differ = 0 ]
