#!/usr/bin/env bash
# Campaigns and explorations on a real batch engine (the book, "Campaigns", "Scale-out"; "The
# fault explorer"): starts a single-node Slurm cluster from Debian's packages (slurm-wlm,
# munge; installed if missing), submits a campaign (deploy/slurm.sh) and an exploration
# (deploy/slurm-explore.sh) as job arrays, merges the shards' lines and checks that they equal
# the same runs here in one piece; then checks the Kubernetes Indexed Job file's YAML. Needs root (it installs packages and starts the daemons) and the release
# binary (cargo build --release --bin asi-lift).
#
#   scripts/ci-slurm.sh [ASI_LIFT]     # default: target/release/asi-lift
set -euo pipefail
cd "$(dirname "$0")/.."
ASI_LIFT="$(realpath "${1:-target/release/asi-lift}")"
[ -x "$ASI_LIFT" ] || { echo "ci-slurm: no binary at $ASI_LIFT (cargo build --release --bin asi-lift)" >&2; exit 1; }

# The campaign: small enough for a CI minute, large enough that every shard has runs with
# faults in them.
RUNS=24
SEED=2026
PROFILE=smoke
SHARDS=4

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q >/dev/null
  apt-get install -y -q slurm-wlm munge >/dev/null
fi

work="$(mktemp -d /tmp/asi-lift-slurm.XXXXXX)"
chmod 755 "$work"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

# munge: the cluster's authentication, with a key of this run's own and its socket in the
# work directory (nothing of the machine's own munge is touched).
# munged wants its key private and its socket's directory open to every user.
mkdir -p "$work/munge" "$work/munge-socket"
chown munge: "$work/munge" "$work/munge-socket"
chmod 700 "$work/munge"
chmod 755 "$work/munge-socket"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chown munge: "$work/munge/munge.key"
chmod 400 "$work/munge/munge.key"
socket="$work/munge-socket/munge.socket"
runuser -u munge -- /usr/sbin/munged --foreground --key-file="$work/munge/munge.key" \
  --socket="$socket" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/munge/munged.log" --seed-file="$work/munge/munged.seed" \
  >"$work/munge/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 20); do [ -S "$socket" ] && break; sleep 0.5; done
[ -S "$socket" ] || { echo "ci-slurm: munged did not start:" >&2; cat "$work/munge/munged.log" >&2; exit 1; }

# Slurm: one node, this machine, with all its cores; state and logs in the work directory.
node="$(hostname -s)"
cpus="$(nproc)"
mem_mb="$(awk '/MemTotal/ { print int($2 / 1024 / 2) }' /proc/meminfo)"
mkdir -p "$work/state" "$work/spool" "$work/log"
cat > "$work/slurm.conf" <<EOF
ClusterName=asi-lift-ci
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=$node CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=ci Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$work/slurm.conf"
/usr/sbin/slurmctld -D -f "$SLURM_CONF" >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
/usr/sbin/slurmd -D -f "$SLURM_CONF" >"$work/log/slurmd.out" 2>&1 &
pids+=($!)
ready=no
for _ in $(seq 60); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then ready=yes; break; fi
  sleep 1
done
if [ "$ready" != yes ]; then
  echo "ci-slurm: the node did not come up:" >&2
  sinfo -h -o '%N %T %c' >&2 || true
  tail -20 "$work"/log/*.log >&2 || true
  exit 1
fi
sinfo -h -o '%N %T %c'

# Submits the job file $2 as an array of $3 tasks (settings in the environment) and waits for
# all; then checks that the shards' lines, merged, equal the local run's file $4 and that
# `asi-lift $1 summarize` gives the same for both. Results go to $work/$1.
slurm_equals_local() {
  local what="$1" job="$2" tasks="$3" local_lines="$4" out="$work/$1"
  mkdir -p "$out"
  echo "ci-slurm: submitting $what in $tasks shards"
  # --wait returns when all tasks are done, with a failure if any task failed.
  if ! OUT_DIR="$out" ASI_LIFT="$ASI_LIFT" \
      timeout 900 sbatch --wait --array=0-$((tasks - 1)) --cpus-per-task=1 --chdir="$work" \
      --output="$work/$what-task-%a.log" "$job"; then
    cat "$work/$what"-task-*.log "$work"/log/*.log >&2 || true
    exit 1
  fi
  sort "$out"/shard-*-of-"$tasks".jsonl > "$out/merged.sorted"
  sort "$local_lines" > "$out/local.sorted"
  if ! cmp -s "$out/merged.sorted" "$out/local.sorted"; then
    echo "ci-slurm: the Slurm shards' $what lines differ from the local run's:" >&2
    diff "$out/merged.sorted" "$out/local.sorted" | head -20 >&2
    exit 1
  fi
  "$ASI_LIFT" "$what" summarize "$out"/shard-*.jsonl > "$out/merged.summary"
  "$ASI_LIFT" "$what" summarize "$local_lines" > "$out/local.summary"
  cmp "$out/merged.summary" "$out/local.summary"
  cat "$out/merged.summary"
  echo "ci-slurm: $(wc -l < "$out/merged.sorted") $what lines from $tasks Slurm shards equal the local run's"
}

# The campaign, here in one piece and as a job array of SHARDS tasks (deploy/slurm.sh).
"$ASI_LIFT" campaign --runs $RUNS --seed $SEED --profile $PROFILE --jobs "$cpus" \
  --out "$work/campaign-local.jsonl" --failures "$work/campaign-local-failures" || [ $? -eq 3 ]
RUNS=$RUNS SEED=$SEED PROFILE=$PROFILE \
  slurm_equals_local campaign deploy/slurm.sh "$SHARDS" "$work/campaign-local.jsonl"

# An exploration: the demo's single faults every 2 s in 10..30 s, here and as an array of 3
# tasks (deploy/slurm-explore.sh).
"$ASI_LIFT" explore demo --every 2s --window 10s..30s --horizon 30s --jobs "$cpus" \
  --out "$work/explore-local.jsonl" --failures "$work/explore-local-failures" 2>/dev/null \
  || [ $? -eq 3 ]
SCENARIO=demo EVERY=2s WINDOW=10s..30s HORIZON=30s \
  slurm_equals_local explore deploy/slurm-explore.sh 3 "$work/explore-local.jsonl"

# The Kubernetes Indexed Job file: YAML that parses, one shard per completion index.
python3 -c "import yaml" 2>/dev/null || python3 -m pip install -q pyyaml
python3 - deploy/k8s-job.yaml <<'EOF'
import sys, yaml
job = yaml.safe_load(open(sys.argv[1]))
spec = job["spec"]
assert job["kind"] == "Job" and spec["completionMode"] == "Indexed", "an Indexed Job"
env = {e["name"]: e["value"] for e in spec["template"]["spec"]["containers"][0]["env"]}
assert int(env["SHARDS"]) == spec["completions"], "SHARDS equals completions"
print(f"ci-slurm: {sys.argv[1]}: an Indexed Job of {spec['completions']} shards")
EOF
