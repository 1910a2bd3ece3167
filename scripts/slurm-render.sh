#!/bin/sh
# Splits a bdpm render over a Slurm job array and merges the parts in a dependent job
# (docs/distributed.md). Usage:
#   scripts/slurm-render.sh SCENE TASKS PASSES_PER_TASK OUTDIR [bdpm render flags…]
# Task i renders passes i·PASSES_PER_TASK … (i+1)·PASSES_PER_TASK − 1 into
# OUTDIR/part<i>.exr (+ .accum.exr); the merge job writes OUTDIR/merged.exr and its set once
# every task has succeeded (afterok). Prints the two job ids. BDPM (default:
# target/release/bdpm, made absolute) must be the same binary on every node for the merge to
# have the bits of a single render.
#
# TASKS and PASSES_PER_TASK must be whole numbers ≥ 1 (they go into the job's command line,
# so nothing else is accepted); every path and flag is quoted for the job's shell, quotes
# included. An OUTDIR that already holds parts or a merge (of an earlier run, perhaps with
# more tasks) is refused: the merge names this run's parts only, but mixing two runs' files in
# one folder invites merging the wrong ones by hand.
set -eu
if [ $# -lt 4 ]; then
    echo "usage: $0 SCENE TASKS PASSES_PER_TASK OUTDIR [bdpm render flags...]" >&2
    exit 1
fi
whole() {
    case "$2" in
        '' | *[!0-9]* | 0*) echo "$0: $1 must be a whole number of at least 1, not '$2'" >&2; exit 1 ;;
    esac
    if [ "${#2}" -gt 9 ]; then
        echo "$0: $1 '$2' is too large" >&2; exit 1
    fi
}
whole TASKS "$2"
whole PASSES_PER_TASK "$3"
tasks=$2; per=$3
# Pass indices are u32: the last one, TASKS·PASSES_PER_TASK − 1, must fit.
if [ "$((tasks * per))" -gt 4294967296 ]; then
    echo "$0: TASKS × PASSES_PER_TASK = $((tasks * per)) passes exceeds 4294967296" >&2
    exit 1
fi
scene=$(realpath "$1"); out=$(realpath -m "$4"); shift 4
bdpm=$(realpath "${BDPM:-target/release/bdpm}")
# Single-quotes a word for the job's shell: ' becomes '\''.
q() { printf "'%s'" "$(printf %s "$1" | sed "s/'/'\\\\''/g")"; }
mkdir -p "$out"
for f in "$out"/part*.exr "$out"/merged.exr; do
    if [ -e "$f" ]; then
        echo "$0: $out already holds $(basename "$f") (files of an earlier run); remove the part*.exr, part*.accum.exr and merged.* files or choose another OUTDIR" >&2
        exit 1
    fi
done
# The flags are quoted once here so that the --wrap shell sees them as they were given.
extra=""
for a in "$@"; do extra="$extra $(q "$a")"; done
parts=""
i=0
while [ "$i" -lt "$tasks" ]; do parts="$parts $(q "$out/part$i.accum.exr")"; i=$((i + 1)); done
array=$(sbatch --parsable --array="0-$((tasks - 1))" --job-name=bdpm-part \
    --output="$out/part-%a.log" \
    --wrap "exec $(q "$bdpm") render $(q "$scene") --first-pass \$((SLURM_ARRAY_TASK_ID * $per)) --passes $per --quiet$extra -o $(q "$out")/part\$SLURM_ARRAY_TASK_ID.exr")
merge=$(sbatch --parsable --dependency="afterok:$array" --job-name=bdpm-merge \
    --output="$out/merge.log" \
    --wrap "exec $(q "$bdpm") merge$parts -o $(q "$out/merged.exr")")
echo "$array $merge"
