#!/usr/bin/env bash
# An asi-lift campaign as a Slurm job array: every array task runs one shard.
#
#   sbatch --array=0-7 deploy/slurm.sh                  # 8 shards of the default campaign
#   RUNS=100000 SEED=42 sbatch --array=0-31 deploy/slurm.sh
#   asi-lift campaign summarize campaign-results/shard-*.jsonl   # when all tasks are done
#
# Slurm numbers array tasks from 0 (SLURM_ARRAY_TASK_ID); --shard counts from 1, so task i
# runs shard i + 1 of SLURM_ARRAY_TASK_COUNT: the runs whose index r has r mod N = i. Every
# run of the campaign belongs to exactly one task. Each task writes its own lines file; the
# reproducers of failing runs go to one shared directory (their names carry the run index,
# so tasks never collide).
#
# Settings (environment): RUNS, SEED, PROFILE (built-in name or a file every node can read),
# OUT_DIR (on a file system shared by the nodes), ASI_LIFT (the binary).
#SBATCH --job-name=asi-lift-campaign
#SBATCH --array=0-7
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
#SBATCH --output=asi-lift-campaign-%A_%a.log
set -euo pipefail

RUNS="${RUNS:-10000}"
SEED="${SEED:-1}"
PROFILE="${PROFILE:-default}"
OUT_DIR="${OUT_DIR:-campaign-results}"
ASI_LIFT="${ASI_LIFT:-asi-lift}"

TASK="${SLURM_ARRAY_TASK_ID:?submit with sbatch --array=0-N (SLURM_ARRAY_TASK_ID is not set)}"
FIRST="${SLURM_ARRAY_TASK_MIN:-0}"
SHARDS="${SLURM_ARRAY_TASK_COUNT:?submit with sbatch --array=0-N (SLURM_ARRAY_TASK_COUNT is not set)}"
K=$((TASK - FIRST + 1))

mkdir -p "$OUT_DIR"
status=0
# --force: a requeued task rewrites its own shard's file.
"$ASI_LIFT" campaign \
  --runs "$RUNS" --seed "$SEED" --profile "$PROFILE" \
  --shard "$K/$SHARDS" --jobs "${SLURM_CPUS_PER_TASK:-1}" \
  --out "$OUT_DIR/shard-$K-of-$SHARDS.jsonl" --force \
  --failures "$OUT_DIR/failures" || status=$?
# Exit status 3: the campaign ran and found failing runs. That is a result, not a failed task.
if [ "$status" -ne 0 ] && [ "$status" -ne 3 ]; then
  exit "$status"
fi
