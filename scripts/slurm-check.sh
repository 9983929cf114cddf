#!/usr/bin/env bash
# Check sharded sweeps against a real Slurm on this machine (as root, Debian):
# installs slurm-wlm and munge, starts munged, slurmctld and slurmd for one node on
# localhost with a minimal slurm.conf, plans a 4-shard sweep, submits it with sbatch,
# waits with squeue (and reads the tasks' states with sacct, or scontrol where there is no
# accounting database), merges, compares with the single-machine run and stops the daemons
# it started.
#
#   scripts/slurm-check.sh                  # the small grid on the bundled sample
#   SWEEP_SESSION=path/to/bts3.csv SWEEP_ARGS="--grid default" scripts/slurm-check.sh
#
# TW_BIN names the program (default: target/release/tactile-workbench, built if missing).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=${TW_BIN:-$ROOT/target/release/tactile-workbench}
SESSION=${SWEEP_SESSION:-$ROOT/sample-sessions/grasp-stability.json}
# shellcheck disable=SC2206
ARGS=(${SWEEP_ARGS:---num-bases 2..24:2 --beta 0.5,1 --gamma 0.5,1,2})
SHARDS=${SWEEP_SHARDS:-4}
WORK=$(mktemp -d /tmp/tw-slurm-check.XXXXXX)
export SLURM_CONF=$WORK/slurm.conf
PIDS=()

say() { echo "== $(date -u +%H:%M:%S) $*"; }

stop() {
  say "stopping the daemons this script started"
  squeue -h -o %i 2>/dev/null | xargs -r scancel 2>/dev/null || true
  for pid in "${PIDS[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
}
trap stop EXIT

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurm-wlm and munge"
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y slurm-wlm munge
fi
dpkg-query -W slurm-wlm munge

if [ ! -x "$BIN" ]; then
  say "building $BIN"
  (cd "$ROOT" && cargo build --release --no-default-features)
fi

say "starting munged"
mkdir -p /etc/munge /run/munge /var/lib/munge /var/log/munge
if [ ! -s /etc/munge/munge.key ]; then
  dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
fi
chown munge:munge /etc/munge /etc/munge/munge.key /run/munge /var/lib/munge /var/log/munge
chmod 0700 /etc/munge /var/lib/munge /var/log/munge
chmod 0400 /etc/munge/munge.key
chmod 0755 /run/munge
runuser -u munge -- munged --pid-file=/run/munge/munged.pid
PIDS+=("$(cat /run/munge/munged.pid)")
munge -n | unmunge >/dev/null

NODE=$(hostname -s)
CPUS=$(nproc)
MEM=$(awk '/MemTotal/ {print int($2 / 1024) - 256}' /proc/meminfo)
mkdir -p "$WORK/state" "$WORK/spool"
cat >"$SLURM_CONF" <<EOF
ClusterName=twcheck
SlurmctldHost=$NODE
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
NodeName=$NODE CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=check Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF

say "starting slurmctld and slurmd ($NODE, $CPUS CPUs, $MEM MB)"
slurmctld -f "$SLURM_CONF"
sleep 1
PIDS+=("$(cat "$WORK/slurmctld.pid")")
slurmd -f "$SLURM_CONF"
sleep 1
PIDS+=("$(cat "$WORK/slurmd.pid")")
for _ in $(seq 30); do
  sinfo -h -o %T | grep -qE '^(idle|mixed)' && break
  sleep 1
done
sinfo

say "single-machine run: stability $(basename "$SESSION") ${ARGS[*]}"
T0=$(date +%s.%N)
nice -n 10 "$BIN" stability "$SESSION" "${ARGS[@]}" --json "$WORK/local.json" --quiet >"$WORK/local.txt"
T1=$(date +%s.%N)
grep -E '^grid:' "$WORK/local.txt"
LOCAL=$(awk "BEGIN { print $T1 - $T0 }")

say "planning $SHARDS shards"
"$BIN" sweep plan stability "$SESSION" "${ARGS[@]}" --shards "$SHARDS" -o "$WORK/plan" --program "$BIN"
cat "$WORK/plan/sweep.sbatch"

say "submitting"
T2=$(date +%s.%N)
JOB=$(sbatch --parsable --nice=10 "$WORK/plan/sweep.sbatch")
echo "job $JOB"
while [ -n "$(squeue -h -j "$JOB" 2>/dev/null)" ]; do
  squeue -h -j "$JOB" -o '%i %T %M' | tr '\n' ';'
  echo
  sleep 10
done
T3=$(date +%s.%N)
SLURM=$(awk "BEGIN { print $T3 - $T2 }")
if sacct -j "$JOB" -X -n -o JobID,State,Elapsed; then
  :
else
  say "sacct has no accounting database here; the tasks' states from scontrol:"
  scontrol show job "$JOB" | grep -E 'JobId=|JobState=|RunTime=' | paste - - - || true
fi
for f in "$WORK"/plan/logs/*.out; do
  echo "--- $(basename "$f")"
  tail -n 3 "$f"
done

"$BIN" sweep status "$WORK/plan"
say "merging and comparing with the single-machine run"
"$BIN" sweep merge "$WORK/plan" -o "$WORK/merged.json" --expect "$WORK/local.json" --quiet
printf 'wall time: single machine %.1f s; %s shards under Slurm %.1f s (submit to last task done)\n' \
  "$LOCAL" "$SHARDS" "$SLURM"
say "slurm check passed (files in $WORK)"
