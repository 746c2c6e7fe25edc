#!/usr/bin/env bash
# Mutation testing of the physics modules (validation/README.md, "Mutation testing";
# results in validation/reports/mutants.md). Runs in place: do not edit the tree meanwhile.
#
#   validation/mutants.sh                          # every physics file, one file at a time
#   validation/mutants.sh src/atmosphere/ozone.rs  # the files named
#   validation/mutants.sh --shard 0/6              # every 6th mutant of all the files
#                                                  # (round robin), in one run
#
# Outcomes (outcomes.json, caught.txt, missed.txt, unviable.txt, timeout.txt) land in
# target/mutants/<file or shard>/mutants.out/. Each mutant takes ~10-20 s on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
shard=
if [ "${1:-}" = --shard ]; then
    shard=$2
    shift 2
fi
files=("$@")
if [ ${#files[@]} -eq 0 ]; then
    files=(
        src/atmosphere/ozone.rs src/atmosphere/rayleigh.rs src/atmosphere/us76.rs
        src/atmosphere/mod.rs src/atmosphere/aerosol_profile.rs
        src/atmosphere/profile_file.rs src/signal.rs src/instrument.rs src/receiver/mod.rs
        src/receiver/channel.rs
        src/detector/mod.rs src/detector/recorder.rs src/detector/dead_time/mod.rs
        src/detector/dead_time/model.rs src/detector/dead_time/record.rs
        src/detector/dead_time/shots.rs src/geometry.rs
        src/scene/sun.rs src/scene/track.rs src/scene/orbit.rs src/scene/curtain.rs
    )
fi
export CARGO_PROFILE_RELEASE_INCREMENTAL=true
run() { # output directory, then cargo-mutants arguments
    local out=$1
    shift
    mkdir -p "$out"
    echo "== $* -> $out"
    # exit status 2 means "some mutants survived": that is the result, not a failure
    nice -n 15 cargo mutants --in-place --no-shuffle --output "$out" "$@" || true
    git diff --quiet -- src || { echo "tree left mutated" >&2; exit 1; }
}
if [ -n "$shard" ]; then
    args=()
    for f in "${files[@]}"; do args+=(--file "$f"); done
    run "target/mutants/shard-${shard/\//-of-}" --shard "$shard" --sharding round-robin "${args[@]}"
else
    for f in "${files[@]}"; do run "target/mutants/${f//\//_}" --file "$f"; done
fi
