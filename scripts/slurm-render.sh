#!/bin/sh
# Splits a bdpm render over a Slurm job array and merges the parts in a dependent job
# (docs/distributed.md). Usage:
#   scripts/slurm-render.sh SCENE TASKS PASSES_PER_TASK OUTDIR [bdpm render flags…]
# Task i renders passes i·PASSES_PER_TASK … (i+1)·PASSES_PER_TASK − 1 into
# OUTDIR/part<i>.exr (+ .accum.exr); the merge job writes OUTDIR/merged.exr and its set once
# every task has succeeded (afterok). Prints the two job ids. BDPM (default:
# target/release/bdpm, made absolute) must be the same binary on every node for the merge to
# have the bits of a single render.
set -eu
if [ $# -lt 4 ]; then
    echo "usage: $0 SCENE TASKS PASSES_PER_TASK OUTDIR [bdpm render flags...]" >&2
    exit 1
fi
scene=$(realpath "$1"); tasks=$2; per=$3; out=$(realpath -m "$4"); shift 4
bdpm=$(realpath "${BDPM:-target/release/bdpm}")
mkdir -p "$out"
# The flags are quoted once here so that the --wrap shell sees them as they were given.
extra=""
for a in "$@"; do extra="$extra '$(printf %s "$a" | sed "s/'/'\\\\''/g")'"; done
array=$(sbatch --parsable --array="0-$((tasks - 1))" --job-name=bdpm-part \
    --output="$out/part-%a.log" \
    --wrap "exec '$bdpm' render '$scene' --first-pass \$((SLURM_ARRAY_TASK_ID * $per)) --passes $per --quiet$extra -o '$out'/part\$SLURM_ARRAY_TASK_ID.exr")
merge=$(sbatch --parsable --dependency="afterok:$array" --job-name=bdpm-merge \
    --output="$out/merge.log" \
    --wrap "exec '$bdpm' merge '$out'/part*.accum.exr -o '$out'/merged.exr")
echo "$array $merge"
