#!/usr/bin/env bash
# What each mode costs per pass, measured side by side: renders SCENE with every MODE in turn,
# REPEATS rounds (the modes interleaved, so a change in the host's speed hits them alike), and
# prints each render's CPU time, wall time and stage times (preparation, photons, camera, from
# the render's JSON report), then per mode the medians and, against the first mode, the median
# of the per-round ratios. On a shared machine quote these medians and ratios, not one run.
# Usage:
#   scripts/stage-times.sh REPEATS PASSES THREADS SCENE.toml MODE...
# e.g. (docs/performance.md, "The weights' cost per pass at the defaults, stage by stage"):
#   scripts/stage-times.sh 6 4 2 scenes/cornell-lambert.toml balance optimal-path
# BDPM=path/to/bdpm picks the binary (default: this checkout's target/release/bdpm).
set -euo pipefail
repeats=$1; passes=$2; threads=$3; scene=$4; shift 4
[ $# -ge 1 ] || { echo "usage: $0 REPEATS PASSES THREADS SCENE MODE..." >&2; exit 2; }
bin=${BDPM:-$(cd "$(dirname "$0")/.." && pwd)/target/release/bdpm}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for r in $(seq "$repeats"); do
  for m in "$@"; do
    /usr/bin/time -f "%U %S %e" -o "$tmp/time.txt" "$bin" render "$scene" --mode "$m" \
      --passes "$passes" --threads "$threads" -o "$tmp/run.exr" --quiet > /dev/null
    python3 - "$tmp/time.txt" "$tmp/run.json" "$m" "$r" >> "$tmp/rows.txt" <<'PY'
import json, sys
user, system, wall = map(float, open(sys.argv[1]).read().split())
t = json.load(open(sys.argv[2]))["timing"]
stages = {s["name"]: s["seconds"] for s in t["pass_stages"]}
print(sys.argv[3], sys.argv[4], user + system, wall, t["prepare_s"],
      stages.get("photons", 0.0), stages.get("camera", 0.0))
PY
    tail -1 "$tmp/rows.txt" | awk '{printf "%-20s round %s: cpu %7.2f s, wall %6.2f s, prep %5.2f s, photons %6.2f s, camera %6.2f s\n", $1, $2, $3, $4, $5, $6, $7}'
  done
done
python3 - "$tmp/rows.txt" "$1" <<'PY'
import statistics as st, sys
rows = [l.split() for l in open(sys.argv[1])]
first = sys.argv[2]
modes = list(dict.fromkeys(r[0] for r in rows))
cols = ["cpu", "wall", "prep", "photons", "camera"]
print("| mode | " + " | ".join(f"median {c} s" for c in cols)
      + " | cpu ratio | wall ratio | photons + camera ratio |")
print("|---|" + "---:|" * (len(cols) + 3))
def values(mode):
    return [list(map(float, r[2:])) for r in rows if r[0] == mode]
base = values(first)
for m in modes:
    v = values(m)
    med = [st.median(x[i] for x in v) for i in range(len(cols))]
    ratio = lambda f: st.median(f(b2, x) for b2, x in zip(base, v))
    cpu = ratio(lambda b, x: x[0] / b[0])
    wall = ratio(lambda b, x: x[1] / b[1])
    stages = ratio(lambda b, x: (x[3] + x[4]) / (b[3] + b[4]))
    print(f"| {m} | " + " | ".join(f"{x:.2f}" for x in med)
          + f" | {cpu:.3f} | {wall:.3f} | {stages:.3f} |")
PY
