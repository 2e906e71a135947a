#!/usr/bin/env bash
# Submits a sharded verification run and its merge:
#
#   examples/slurm/submit.sh SPEC TASK TRIALS SHARDS [SEED]
#
# e.g. `examples/slurm/submit.sh tasks/pick_place.truth.json pick_place 2000 8` runs 8 array
# tasks of 250 trials each, then the merge job. Prints the merge job's id.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
spec=$1 task=$2 trials=$3 shards=$4 seed=${5:-0}
array=$(sbatch --parsable --array=0-$((shards - 1)) "$here/execute.sbatch" \
    "$spec" "$task" "$trials" "$seed")
sbatch --parsable --dependency=afterok:"${array%%;*}" "$here/merge.sbatch" "$spec" "$task"
