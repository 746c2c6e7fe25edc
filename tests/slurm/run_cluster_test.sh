#!/usr/bin/env bash
# A real test of deploy/slurm/ on a one-node Slurm cluster started here, as root, from
# the distribution's packages (Debian: slurmctld, slurmd, slurm-client, munge; .ci/run
# installs them). It installs nothing itself.
#
# 1. writes a minimal slurm.conf (this host as the only node, no cgroup plugins,
#    state, spool, logs and the munge socket in a temporary directory, random ports);
# 2. starts munged, slurmctld and slurmd in the foreground as children of this script
#    (no systemd needed), and waits until the node is idle;
# 3. submits, through deploy/slurm/submit.sh, a 4-task `simulate` array job with its
#    dependent merge, a 4-task `validate` array job with its dependent combine, and a
#    4-task `onboard` array job with its dependent merge and combine;
# 4. waits for every job, checks that each COMPLETED, that the merged file equals the
#    single run's byte for byte (cmp), that the combined verdict is the single
#    validate's (cmp of their tables), and that the merged product and combined report
#    are the single onboard run's (cmp);
# 5. stops every daemon and deletes the directory, on success, failure or interruption.
#
# Usage: tests/slurm/run_cluster_test.sh [LIDARSIM_BINARY]  (default target/release/lidarsim)
# Prints "slurm cluster test: PASSED" last when it passes; exit 0 on success.
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)
lidarsim=$(realpath "${1:-$repo/target/release/lidarsim}")
tasks=4
timeout_s=${SLURM_TEST_TIMEOUT:-150}

say() { echo "slurm cluster test: $*" >&2; }
fail() {
  say "FAILED: $*"
  exit 1
}

[ "$(id -u)" = 0 ] || fail "must run as root (the test cluster's daemons run as root)"
for cmd in munged mungekey slurmctld slurmd sbatch squeue scontrol sinfo scancel; do
  command -v "$cmd" >/dev/null || fail "$cmd not found (Debian: apt-get install slurmctld slurmd slurm-client munge)"
done
[ -x "$lidarsim" ] || fail "no lidarsim binary at $lidarsim (cargo build --release)"

tmp=$(mktemp -d /tmp/lidarsim-slurm.XXXXXX)
chmod 711 "$tmp"
pids=()
cleanup() {
  local status=$?
  if [ -f "$tmp/slurm.conf" ]; then
    scancel --quiet --user=root 2>/dev/null || true
  fi
  for pid in "${pids[@]}"; do
    kill -TERM "$pid" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    # wait up to 10 s for each, then kill it
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -KILL "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  if [ "$status" != 0 ]; then
    for log in slurmctld.log slurmd.log munged.log; do
      [ -f "$tmp/$log" ] && { echo "--- last lines of $log" >&2; tail -n 15 "$tmp/$log" >&2; }
    done
    for log in "$tmp"/jobs/*.shards/*.log; do
      [ -f "$log" ] && { echo "--- $log" >&2; tail -n 5 "$log" >&2; }
    done
  fi
  rm -rf "$tmp"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP

host=$(hostname -s)
# ports of this cluster, away from the defaults (6817/6818) and from each other run
port=$((20000 + RANDOM % 20000))
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/jobs"
chmod 711 "$tmp/munge"

# --- munge: a key of our own, a socket in the temporary directory
mungekey --create --keyfile="$tmp/munge/munge.key" --bits=1024 2>/dev/null \
  || dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --foreground --force \
  --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munged.log" \
  --seed-file="$tmp/munge/munged.seed" >>"$tmp/munged.log" 2>&1 &
pids+=($!)

cat >"$tmp/slurm.conf" <<CONF
ClusterName=lidarsim-test
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/munge.socket
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SchedulerParameters=kill_invalid_depend
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MinJobAge=600
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$tmp/slurm.conf

# wait for munged's socket before the Slurm daemons authenticate through it
for _ in $(seq 50); do [ -S "$tmp/munge/munge.socket" ] && break; sleep 0.2; done
[ -S "$tmp/munge/munge.socket" ] || fail "munged did not start"

slurmctld -D -i -f "$SLURM_CONF" >>"$tmp/slurmctld.log" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >>"$tmp/slurmd.log" 2>&1 &
pids+=($!)

say "waiting for node $host (slurmctld on port $port)"
state=""
for _ in $(seq 120); do
  state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || fail "node $host not idle after 60 s (state: '${state:-none}')"

# --- the jobs, as a user would submit them
export LIDARSIM=$lidarsim SOURCE_DATE_EPOCH=1700000000
config=$repo/configs/paper/scenario1.toml
cd "$tmp/jobs"
ids=$("$repo/deploy/slurm/submit.sh" simulate "$config" "$tmp/jobs/merged.h5" "$tasks" \
  --profiles 10)
read -r sim_array sim_merge <<<"$ids"
ids=$("$repo/deploy/slurm/submit.sh" validate "$config" "$tmp/jobs/verdict.txt" "$tasks" \
  --realizations 400 --seed 3)
read -r val_array val_combine <<<"$ids"
caliop=$repo/configs/instruments/caliop_532.toml
onboard=(--set acquisition.top_altitude_km=40 --set acquisition.bottom_altitude_km=-2
  --set acquisition.profiles=30 --scheme caliop --scheme uniform:7)
ids=$("$repo/deploy/slurm/submit.sh" onboard "$caliop" "$tmp/jobs/product.h5" "$tasks" "${onboard[@]}")
read -r ob_array ob_merge <<<"$ids"
say "submitted simulate array $sim_array + merge $sim_merge, validate array $val_array + combine $val_combine, onboard array $ob_array + merge $ob_merge"

# the single runs to compare with, meanwhile
"$lidarsim" simulate "$config" --profiles 10 -o "$tmp/jobs/whole.h5" 2>/dev/null
"$lidarsim" validate "$config" --realizations 400 --seed 3 >"$tmp/jobs/single.txt" 2>/dev/null
"$lidarsim" onboard "$caliop" "${onboard[@]}" -o "$tmp/jobs/whole_product.h5" \
  --report "$tmp/jobs/whole_product.csv" 2>/dev/null

deadline=$((SECONDS + timeout_s))
while [ -n "$(squeue -h -o %i 2>/dev/null)" ]; do
  queue=$(squeue -h -o '%i %T %r' | tr '\n' ';')
  # a task failed: its dependent job can never run
  case $queue in *DependencyNeverSatisfied*) fail "a task failed, its dependent job cannot run: $queue" ;; esac
  [ $SECONDS -lt $deadline ] || fail "jobs still queued or running after ${timeout_s} s: $queue"
  sleep 1
done

# every job, each array task included, must have COMPLETED
for job in "$sim_array" "$sim_merge" "$val_array" "$val_combine" "$ob_array" "$ob_merge"; do
  states=$(scontrol show job "$job" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | sort | uniq -c | tr -s ' ' | tr '\n' ';')
  count=$(scontrol show job "$job" | grep -c 'JobState=COMPLETED' || true)
  want=1
  [ "$job" = "$sim_array" ] || [ "$job" = "$val_array" ] || [ "$job" = "$ob_array" ] && want=$tasks
  [ "$count" = "$want" ] || fail "job $job: $count of $want tasks COMPLETED ($states)"
done
say "all jobs COMPLETED: $tasks-task simulate array, merge (afterok), $tasks-task validate array, combine (afterok), $tasks-task onboard array, merge and combine (afterok)"

shards=$(find "$tmp/jobs/merged.h5.shards" -name 'shard-*.h5' | wc -l)
[ "$shards" = "$tasks" ] || fail "$shards shard files, not $tasks"
cmp "$tmp/jobs/whole.h5" "$tmp/jobs/merged.h5" || fail "the merged file differs from the single run's"
say "cmp: merged.h5 of $tasks shards is byte-identical to the single run's file"
cmp "$tmp/jobs/single.txt" "$tmp/jobs/verdict.txt" || fail "the combined verdict differs from the single validate's"
say "cmp: the combined validate table of $tasks partials equals the single run's ($(tail -n 1 "$tmp/jobs/verdict.txt" | cut -d: -f1))"
cmp "$tmp/jobs/whole_product.h5" "$tmp/jobs/product.h5" || fail "the merged product differs from the single onboard run's"
cmp "$tmp/jobs/whole_product.csv" "$tmp/jobs/product.csv" || fail "the combined report differs from the single onboard run's"
say "cmp: product.h5 and product.csv of $tasks onboard shards are byte-identical to the single onboard run's"
say "PASSED"
