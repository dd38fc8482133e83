#!/usr/bin/env bash
# An asi-lift fault exploration as a Slurm job array: every array task runs one shard.
#
#   sbatch --array=0-7 deploy/slurm-explore.sh                       # 8 shards of the demo, every 10 ms
#   SCENARIO=safe-drive EVERY=100ms sbatch --array=0-31 deploy/slurm-explore.sh
#   asi-lift explore summarize explore-results/shard-*.jsonl     # when all tasks are done
#
# Slurm numbers array tasks from 0 (SLURM_ARRAY_TASK_ID); --shard counts from 1, so task i
# runs shard i + 1 of SLURM_ARRAY_TASK_COUNT: the forks whose index f has f mod N = i. Every
# fork of the exploration belongs to exactly one task, and the lines are the same whatever
# the shards. Each task writes its own lines file; the reproducers of violating forks go to
# one shared directory (their names carry the fork index, so tasks never collide).
#
# Settings (environment): SCENARIO (built-in name or a file every node can read), EVERY,
# WINDOW (START..END, empty: the whole scenario), HORIZON, OUT_DIR (on a file system shared
# by the nodes), ASI_LIFT (the binary).
#SBATCH --job-name=asi-lift-explore
#SBATCH --array=0-7
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
#SBATCH --output=asi-lift-explore-%A_%a.log
set -euo pipefail

SCENARIO="${SCENARIO:-demo}"
EVERY="${EVERY:-10ms}"
WINDOW="${WINDOW:-}"
HORIZON="${HORIZON:-60s}"
OUT_DIR="${OUT_DIR:-explore-results}"
ASI_LIFT="${ASI_LIFT:-asi-lift}"

TASK="${SLURM_ARRAY_TASK_ID:?submit with sbatch --array=0-N (SLURM_ARRAY_TASK_ID is not set)}"
FIRST="${SLURM_ARRAY_TASK_MIN:-0}"
SHARDS="${SLURM_ARRAY_TASK_COUNT:?submit with sbatch --array=0-N (SLURM_ARRAY_TASK_COUNT is not set)}"
K=$((TASK - FIRST + 1))

mkdir -p "$OUT_DIR"
window=()
if [ -n "$WINDOW" ]; then window=(--window "$WINDOW"); fi
status=0
# --force: a requeued task rewrites its own shard's file.
"$ASI_LIFT" explore "$SCENARIO" --every "$EVERY" "${window[@]}" --horizon "$HORIZON" \
  --shard "$K/$SHARDS" --jobs "${SLURM_CPUS_PER_TASK:-1}" \
  --out "$OUT_DIR/shard-$K-of-$SHARDS.jsonl" --force \
  --failures "$OUT_DIR/failures" 2>"$OUT_DIR/shard-$K-of-$SHARDS.sheet" || status=$?
# Exit status 3: the exploration ran and found violations. That is a result, not a failed task.
if [ "$status" -ne 0 ] && [ "$status" -ne 3 ]; then
  cat "$OUT_DIR/shard-$K-of-$SHARDS.sheet" >&2
  exit "$status"
fi
