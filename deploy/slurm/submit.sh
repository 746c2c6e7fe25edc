#!/usr/bin/env bash
# Submits a sharded lidarsim run to Slurm: an array job of TASKS tasks, then the job
# that merges (simulate, onboard) or combines (validate, onboard) their outputs, chained
# with --dependency=afterok so that it starts only when every task succeeded.
#
#   deploy/slurm/submit.sh simulate CONFIG OUT.h5  TASKS [simulate options...]
#   deploy/slurm/submit.sh validate CONFIG OUT.txt TASKS [validate options...]
#   deploy/slurm/submit.sh onboard  CONFIG OUT.h5  TASKS --scheme ... [onboard options...]
#     (the product OUT.h5 and its report OUT.csv)
#
# The shards go to OUT.shards/ (LIDARSIM_WORK to choose), the jobs' logs beside them.
# Prints the two job ids on stdout ("ARRAY_ID NEXT_ID"), what it did on stderr.
# Environment: LIDARSIM (the binary, default lidarsim on PATH; the jobs inherit it),
# SBATCH_OPTS (more sbatch options for every job, e.g. "--partition=long --time=2:00:00"),
# SOURCE_DATE_EPOCH (reproducible bytes; the jobs inherit it). docs/scale.md explains.
set -euo pipefail
usage() {
  echo "usage: $0 simulate|validate|onboard CONFIG OUT TASKS [lidarsim options...]" >&2
  exit 2
}
[ $# -ge 4 ] || usage
kind=$1 config=$2 out=$3 tasks=$4
shift 4
case $kind in
  simulate) array_script=simulate_array.sbatch next_script=merge.sbatch ;;
  validate) array_script=validate_array.sbatch next_script=combine.sbatch ;;
  onboard) array_script=onboard_array.sbatch next_script=onboard_merge.sbatch ;;
  *) usage ;;
esac
[[ $tasks =~ ^[1-9][0-9]*$ ]] || { echo "$0: TASKS must be a whole number >= 1, not '$tasks'" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
work=${LIDARSIM_WORK:-$out.shards}
mkdir -p "$work"
# shellcheck disable=SC2086 # SBATCH_OPTS is a list of options
array=$(sbatch --parsable ${SBATCH_OPTS:-} --array="0-$((tasks - 1))" \
  --output="$work/%x-%a.log" "$here/$array_script" "$config" "$work" "$@")
array=${array%%;*} # --parsable prints "id" or "id;cluster"
# shellcheck disable=SC2086
next=$(sbatch --parsable ${SBATCH_OPTS:-} --dependency="afterok:$array" \
  --output="$work/%x.log" "$here/$next_script" "$out" "$work")
next=${next%%;*}
echo "submitted $kind: array job $array ($tasks tasks, into $work), then job $next (afterok:$array) writing $out" >&2
echo "$array $next"
