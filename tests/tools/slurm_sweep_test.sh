#!/usr/bin/env bash
# `ecrf report sweep --plan` on a real Slurm: a one-node cluster on this machine (munged,
# slurmctld and slurmd on localhost, each with its state, socket, key and logs in a temporary
# directory) runs the built-in scene's small sweep as a job array. The collected report must hold
# the same bytes per point as the same sweep run locally; a task that did not finish must be named
# with its log, and resubmitting the array must rerun only that task.
#   slurm_sweep_test.sh ECRF_BINARY
# Exits 77 (skipped) when Slurm or munge is not installed (scripts/install-deps.sh --test
# installs both). Stops its daemons when done, passed or not.
set -euo pipefail
ecrf="$(readlink -f "$1")"
export PATH="$PATH:/usr/sbin:/sbin"
for tool in munged munge slurmctld slurmd sbatch squeue sinfo python3; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "SlurmSweep skipped: $tool is not installed (scripts/install-deps.sh --test)"
    exit 77
  fi
done

work="$(mktemp -d /tmp/ecrf_slurm_XXXXXX)"
chmod 755 "$work"
cluster="$work/cluster"
mkdir -p -m 711 "$cluster/munge"
mkdir -p "$cluster/state" "$cluster/spool" "$cluster/log"
stop() {
  for pid in "$cluster/slurmd.pid" "$cluster/slurmctld.pid" "$cluster/munge/munged.pid"; do
    [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true
  done
  sleep 1
  rm -rf "$work"
}
fail() {
  echo "SlurmSweep: $*" >&2
  for f in "$cluster"/log/*.log "$cluster"/munge/munged.log; do
    [ -f "$f" ] && { echo "--- $f" >&2; tail -n 20 "$f" >&2; }
  done
  exit 1
}
trap stop EXIT

# munge: its own key and socket, so a machine's own munge (if any) is left alone.
dd if=/dev/urandom of="$cluster/munge/munge.key" bs=1024 count=1 2>/dev/null
chmod 600 "$cluster/munge/munge.key"
sock="$cluster/munge/munge.sock"
munged --force --socket="$sock" --key-file="$cluster/munge/munge.key" \
  --pid-file="$cluster/munge/munged.pid" --log-file="$cluster/munge/munged.log" \
  --seed-file="$cluster/munge/seed" || fail "munged did not start"
munge -S "$sock" -n | unmunge -S "$sock" >/dev/null || fail "munge cannot encode and decode"

# Slurm: controller and node daemon on localhost, ports from this process's id.
port=$((20000 + ($$ % 10000) * 2))
user="$(id -un)"
mem_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 256))
export SLURM_CONF="$cluster/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=ecrftest
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$sock
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/log/slurmctld.log
SlurmdLogFile=$cluster/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem_mb State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -i || fail "slurmctld did not start"
slurmd -N localhost || fail "slurmd did not start"
for _ in $(seq 60); do
  state="$(sinfo -h -o %t 2>/dev/null || true)"
  [ "$state" = "idle" ] && break
  sleep 1
done
[ "$state" = "idle" ] || fail "the node is '$state', not idle, after 60 s"
echo "SlurmSweep: one-node cluster up (ports $port-$((port + 1)))"

cd "$work"
sweep=(report sweep --scene builtin --rates low,medium --iters 100 --batch 512 --final-grid 48
       --max-test-views 1)
"$ecrf" "${sweep[@]}" --threads 2 -o local >local.log 2>&1 || { cat local.log; fail "the local sweep failed"; }
"$ecrf" "${sweep[@]}" -o slurm --plan --task-cpus 1

# Submits the plan's array (options on the command line override the script's #SBATCH lines) and
# waits for it to leave the queue.
run_array() {
  local jid
  jid="$(sbatch --parsable --mem=1G slurm/plan/sweep.sbatch)" || fail "sbatch refused the plan"
  for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$jid" 2>/dev/null)" ] && return 0
    sleep 1
  done
  fail "job array $jid still queued or running after 600 s"
}
run_array
bash slurm/plan/collect.sh >collect.log 2>&1 || { cat collect.log; fail "collect failed"; }

same_points() {
  for point in rate_low rate_medium; do
    cmp "local/runs/$point/scene.ecrf" "slurm/runs/$point/scene.ecrf" ||
      fail "$point: the Slurm task wrote other bytes than the local sweep"
  done
  python3 - <<'PY' || fail "the reports differ"
import json
a = json.load(open("local/report.json"))["points"]
b = json.load(open("slurm/report.json"))["points"]
keys = ("run_dir", "file_bytes", "decoded_psnr", "decoded_ssim", "float_psnr", "lambda_e")
assert len(a) == len(b) == 2, (len(a), len(b))
for p, q in zip(a, b):
    for k in keys:
        assert p[k] == q[k], (p["run_dir"], k, p[k], q[k])
    print("  %-18s %7d bytes, %.4f dB in both" % (p["run_dir"], p["file_bytes"], p["decoded_psnr"]))
PY
}
same_points

# A task that did not finish: collect names it with its log and fails; the resubmitted array
# trains only that point again (the other task finds its run finished).
rm slurm/runs/rate_low/metrics.json
if bash slurm/plan/collect.sh >collect2.log 2>&1; then
  fail "collect succeeded with an unfinished point"
fi
grep -q "rate_low (task 0, log $work/slurm/plan/logs/task_0.log)" collect2.log ||
  { cat collect2.log; fail "collect did not name the unfinished task's log"; }
run_array
grep -q "finished already" slurm/plan/logs/task_1.log || fail "task 1 was trained again"
bash slurm/plan/collect.sh >collect3.log 2>&1 || { cat collect3.log; fail "collect failed after the rerun"; }
same_points

# The same plan without Slurm: run_local.sh reruns what is unfinished (GNU parallel when there,
# one after another otherwise) and collects.
rm slurm/runs/rate_medium/metrics.json
jobs=1
command -v parallel >/dev/null 2>&1 && jobs=2
bash slurm/plan/run_local.sh "$jobs" >local_run.log 2>&1 || { cat local_run.log; fail "run_local.sh $jobs failed"; }
grep -q "finished already" slurm/plan/logs/task_0.log || fail "run_local.sh trained task 0 again"
same_points
echo "SlurmSweep: 1 passed, 0 failed"
