#!/usr/bin/env bash
# Equal wall time, side by side: renders each scene file given with `bdpm render
# --time-budget SECONDS --threads THREADS`, in turn, REPEATS times (seeds 1..REPEATS), and
# compares every image with REFERENCE (`bdpm compare`: rel. RMSE and relMSE with the
# reference's own error subtracted). Prints one line per render and, per scene file, the
# medians of the error and of the wall time the render took. A render stops after the pass
# that reaches the budget, so its time is a little over it; the "at the budget" column scales
# each render's rel. RMSE by √(its time / budget), as a variance-dominated error falls (a bias
# does not fall, so this overstates the error of a biased render).
# Usage:
#   scripts/equal-time.sh REFERENCE.exr SECONDS THREADS REPEATS SCENE.toml...
# A SCENE argument may carry flags for that file's renders alone, in one quoted word, e.g.
#   "scenes/cornell-lambert.toml --mode balance --light-tracing true".
# e.g. (docs/results.md, "Defaults that win at equal time"):
#   scripts/equal-time.sh out/ref/lambert-light-400.exr 20 2 3 \
#     scenes/preprint/cornell-lambert.toml scenes/cornell-lambert.toml
# EXTRA="--radius 0.5px" adds flags to every render; FIRST_SEED=4 starts the seeds at 4
# instead of 1 (more runs without repeating the earlier ones).
set -euo pipefail
ref=$1; budget=$2; threads=$3; repeats=$4; shift 4
[ -f "$ref" ] || { echo "equal-time.sh: no reference $ref" >&2; exit 2; }
bin=${BDPM:-$(cd "$(dirname "$0")/.." && pwd)/target/release/bdpm}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
read -r -a extra <<< "${EXTRA:-}"
first=${FIRST_SEED:-1}
for i in $(seq "$first" $((first + repeats - 1))); do
  for scene in "$@"; do
    key=$(echo "$scene" | tr '/. ' '___')
    read -r -a words <<< "$scene"
    "$bin" render "${words[@]}" --time-budget "$budget" --threads "$threads" --seed "$i" \
      --passes 100000 "${extra[@]}" -o "$tmp/run.exr" --quiet > /dev/null
    line=$("$bin" compare "$tmp/run.exr" "$ref" | grep "as reference")
    python3 - "$tmp/run.json" "$line" "$scene" "$i" "$budget" >> "$tmp/$key.txt" <<'PY'
import json, re, sys
d = json.load(open(sys.argv[1])); t = d["timing"]
m = re.search(r"rel\. RMSE ([0-9.]+)%, relMSE ([0-9.e+-]+)", sys.argv[2])
wall = t["prepare_s"] + t["render_s"]
budget = float(sys.argv[5])
print(f'{float(m.group(1)):.3f} {float(m.group(2)):.4e} {wall:.2f} {d["passes_done"]} '
      f'{float(m.group(1)) * (wall / budget) ** 0.5:.3f}')
print(f'{sys.argv[3]} seed {sys.argv[4]}: rel. RMSE {m.group(1)}%, relMSE {m.group(2)}, '
      f'{wall:.1f} s, {d["passes_done"]} passes', file=sys.stderr)
PY
  done
done
echo "| scene file | renders | median rel. RMSE | median rel. RMSE at the budget | median relMSE | median wall s | median passes |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for scene in "$@"; do
  key=$(echo "$scene" | tr '/. ' '___')
  python3 - "$tmp/$key.txt" "$scene" <<'PY'
import statistics as st, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1])]
med = lambda k: st.median(r[k] for r in rows)
print(f"| {sys.argv[2]} | {len(rows)} | {med(0):.2f}% | {med(4):.2f}% | {med(1):.3e} | {med(2):.1f} | {med(3):.0f} |")
PY
done
