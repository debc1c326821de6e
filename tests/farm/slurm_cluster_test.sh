#!/usr/bin/env bash
# The small inn cooked through a private single-node Slurm cluster (tools/farm/lightpatch-farm)
# must give the bytes of a local `lightpatch cook`. The cluster is this test's own: slurm.conf,
# ports, spool and state folders and a munged with a temporary key, all in one temporary folder,
# all stopped and removed at the end, on failure too. If Slurm cannot start, the test fails and
# says why (./run deps installs slurm-wlm and munge).
#
#   slurm_cluster_test.sh LIGHTPATCH LIGHTPATCH_INN LIGHTPATCH_FARM
#
# As a benchmark (README, "Cooking on a build farm"): LIGHTPATCH_FARM_QUALITY (default draft) and
# LIGHTPATCH_FARM_TASKS (default 2, each of 1 core; 1: one task of every core) choose the cook;
# the summary compares the farm's CPU and wall time with the local cook's.
set -euo pipefail

LP=$1 INN=$2 FARM=$3
QUALITY=(--quality "${LIGHTPATCH_FARM_QUALITY:-draft}")
TASKS=${LIGHTPATCH_FARM_TASKS:-2}
TASK_CPUS=1
[ "$TASKS" = 1 ] && TASK_CPUS=$(nproc)

fail() { echo "FAIL: $*" >&2; exit 1; }
daemon() {  # the path of a daemon (sbin is not always on a user's PATH)
  command -v "$1" 2>/dev/null || { [ -x "/usr/sbin/$1" ] && echo "/usr/sbin/$1"; } ||
    fail "$1 not found: install slurm-wlm and munge (./run deps)"
}
MUNGED=$(daemon munged)
SLURMCTLD=$(daemon slurmctld)
SLURMD=$(daemon slurmd)
for c in sbatch squeue sinfo scancel munge; do command -v "$c" >/dev/null || fail "$c not found (./run deps)"; done

T=$(mktemp -d "${TMPDIR:-/tmp}/lightpatch-slurm.XXXXXX")
export SLURM_CONF=$T/slurm.conf

pid_of() { [ -f "$1" ] && cat "$1" 2>/dev/null || true; }

cleanup() {
  local rc=$?
  set +e
  if [ -f "$SLURM_CONF" ] && [ -n "$(pid_of "$T/slurmctld.pid")" ]; then
    scancel --user "$(id -un)" >/dev/null 2>&1
    for _ in $(seq 1 20); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.5; done
  fi
  # Only the daemons this test started, by the pids they wrote.
  local pids=() f p
  for f in "$T/slurmd.pid" "$T/slurmctld.pid" "$T/munge/munged.pid"; do
    p=$(pid_of "$f")
    [ -n "$p" ] && kill "$p" 2>/dev/null && pids+=("$p")
  done
  for _ in $(seq 1 50); do
    local alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
  if [ $rc -ne 0 ]; then
    for f in "$T"/log/*.log "$T"/munge/munged.log "$T"/jobs/farm/*/*.log; do
      [ -f "$f" ] && { echo "--- $f (last lines)"; tail -n 15 "$f"; }
    done >&2
  fi
  rm -rf "$T"
  exit $rc
}
trap cleanup EXIT

# Two free TCP ports next to each other (a connection to a free port is refused).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
PORT=0
for _ in $(seq 1 50); do
  p=$((20000 + RANDOM % 30000))
  if port_free "$p" && port_free $((p + 1)); then PORT=$p; break; fi
done
[ "$PORT" -ne 0 ] || fail "no two free TCP ports found"

# munged with a key of its own; its socket is what slurm.conf's AuthInfo names.
mkdir -p "$T/munge" "$T/key" "$T/state" "$T/spool" "$T/log"
chmod 700 "$T/key"
head -c 1024 /dev/urandom > "$T/key/munge.key"
chmod 600 "$T/key/munge.key"
"$MUNGED" --key-file="$T/key/munge.key" --socket="$T/munge/socket" \
  --pid-file="$T/munge/munged.pid" --log-file="$T/munge/munged.log" \
  --seed-file="$T/munge/seed" --force ||
  fail "munged did not start: $(tail -n 3 "$T/munge/munged.log" 2>/dev/null)"
echo probe | munge -S "$T/munge/socket" | unmunge -S "$T/munge/socket" >/dev/null ||
  fail "munge round trip failed"

HOST=$(hostname -s)
USER_NAME=$(id -un)
CPUS=$(nproc)
cat > "$SLURM_CONF" <<EOF
ClusterName=lightpatch-test
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=$USER_NAME
SlurmdUser=$USER_NAME
AuthType=auth/munge
AuthInfo=socket=$T/munge/socket
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=1024 State=UNKNOWN
PartitionName=cook Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF

t0=$SECONDS
"$SLURMCTLD" -f "$SLURM_CONF" -i || fail "slurmctld did not start: $(tail -n 5 "$T/log/slurmctld.log" 2>/dev/null)"
"$SLURMD" -f "$SLURM_CONF" -N "$HOST" || fail "slurmd did not start: $(tail -n 5 "$T/log/slurmd.log" 2>/dev/null)"
state=""
for _ in $(seq 1 120); do
  state=$(sinfo -h -N -o %T 2>/dev/null | head -1)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || fail "the node did not come up (state '$state'): $(tail -n 5 "$T/log/slurmctld.log")"
echo "cluster up in $((SECONDS - t0)) s (ports $PORT, $((PORT + 1)); $CPUS cpus)"

"$INN" generate -o "$T/inn.glb" --scale small >/dev/null
TIMEFORMAT="local cook: %R s wall, %U s user, %S s sys"
{ time "$LP" cook "$T/inn.glb" -o "$T/local.lpk" "${QUALITY[@]}" --quiet; } 2> "$T/local.time"
cat "$T/local.time"

# A lightpatch that fails its first run: the farm's retry must cover it.
cat > "$T/flaky-lightpatch" <<EOF
#!/usr/bin/env bash
if [ "\$1" = cook-job ] && [ ! -f "$T/failed-once" ]; then
  touch "$T/failed-once"
  echo "flaky-lightpatch: failing on purpose" >&2
  exit 1
fi
exec "$LP" "\$@"
EOF
chmod +x "$T/flaky-lightpatch"

t1=$(date +%s.%N)
TIMEFORMAT="plan: %R s wall, %U s user, %S s sys"
{ time "$LP" plan "$T/inn.glb" -o "$T/jobs" "${QUALITY[@]}" --quiet > "$T/names.txt"; } 2> "$T/plan.time"
cat "$T/plan.time"
jobs=$(wc -l < "$T/names.txt")
[ "$jobs" -ge 2 ] || fail "plan printed $jobs jobs"
"$FARM" submit "$T/jobs" -o "$T/farm.lpk" --tasks "$TASKS" --cpus-per-task "$TASK_CPUS" --gather-cpus "$CPUS" --retries 1 \
  --lightpatch "$T/flaky-lightpatch"
"$FARM" status "$T/jobs"
"$FARM" wait "$T/jobs" --timeout 500 || fail "the farm's cook failed"
t2=$(date +%s.%N)
grep -h "attempt\|assemble on" "$T"/jobs/farm/*/*.log || true
# CPU: every process's user + sys. Scheduling overhead: the wall time from plan to pack less the
# chain's own wall times (plan, the gather job, the longest array task, assemble; retries
# included), i.e. what submission, queueing and the dependencies' release cost.
for f in "$T"/plan.time "$T"/jobs/farm/*/*.log; do
  echo "$(basename "$f")" "$(awk '/ s user, / { for (i = 1; i <= NF; i++) {
    if ($i == "wall,") w += $(i - 2); if ($i == "user," || $i == "sys") c += $(i - 2) } }
    END { printf "%.3f %.3f", w, c }' "$f")"
done | awk -v t1="$t1" -v t2="$t2" -v local_line="$(cat "$T/local.time")" '
  { cpu += $3; if ($1 ~ /^task-/) { if ($2 > task) task = $2 } else chain += $2 }
  END {
    wall = t2 - t1; split(local_line, w, " "); lw = w[3]; lc = w[6] + w[9]
    printf "farm: %.2f s CPU, %.2f s wall (plan to pack; scheduling overhead %.2f s); " \
           "local cook: %.2f s CPU, %.2f s wall; ratios CPU %.2fx, wall %.2fx\n", cpu, wall,
           wall - chain - task, lc, lw, cpu / lc, wall / lw }'
[ -f "$T/failed-once" ] || fail "the flaky run did not happen"
grep -q "attempt 0 failed" "$T"/jobs/farm/*/*.log || fail "no job logged its retry"

cmp "$T/local.lpk" "$T/farm.lpk" || fail "the pack from the cluster differs from the local cook"
[ -z "$("$LP" jobs "$T/jobs" --pending 2>/dev/null)" ] || fail "jobs left without a result"
echo "PASS: $jobs jobs on Slurm, pack identical to the local cook ($(stat -c %s "$T/farm.lpk") bytes)"
