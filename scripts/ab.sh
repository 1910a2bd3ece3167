#!/usr/bin/env bash
# Times the stages of `bdpm render` for several binaries side by side, interleaved, N times
# each, and prints the minimum and median of every stage (seconds, from each run's JSON report).
# Used for the before/after figures in docs/performance.md. Example:
#   scripts/ab.sh 5 cornell-lambert optimal 256x256 1 1 /tmp/bdpm-before target/release/bdpm
# (N, scene, mode, resolution, passes, threads, then the binaries; build an older binary with
# `git worktree add /tmp/old REV && (cd /tmp/old && cargo build --release)`). A binary written
# BINARY@MODE runs that mode instead, so modes of one binary compare side by side:
#   scripts/ab.sh 5 cornell-glossy balance 256x256 1 1 target/release/bdpm target/release/bdpm@optimal-path
# scenes/cornell-glossy.toml sets adaptive_radius (docs/results.md, "A one-pass pilot…"): a binary
# older than ff11630 cannot read it, and the figures of docs/performance.md before that ran it
# with one radius; give "preprint/cornell-glossy" to time a file every binary reads.
# EXTRA="--light-tracing true" adds flags to every render.
set -euo pipefail
cd "$(dirname "$0")/.."
read -r -a extra <<< "${EXTRA:-}"
n=$1; scene=$2; mode=$3; res=$4; passes=$5; threads=$6; shift 6
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for i in $(seq "$n"); do
  for b in "$@"; do
    key=$(echo "$b" | tr '/@' '__')
    bin=${b%@*}; m=$mode
    [[ "$b" == *@* ]] && m=${b##*@}
    "$bin" render "scenes/$scene.toml" --mode "$m" --resolution "$res" --passes "$passes" \
      --threads "$threads" "${extra[@]}" -o "$tmp/run.exr" --quiet > /dev/null
    python3 - "$tmp/run.json" >> "$tmp/$key.txt" <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); t = d["timing"]
st = {s["name"]: s["seconds"] for s in t["pass_stages"]}
print(t["prepare_s"], st.get("photons", 0.0), st.get("camera", 0.0), t["prepare_s"] + t["render_s"])
PY
  done
done
for b in "$@"; do
  key=$(echo "$b" | tr '/@' '__')
  echo "$b"
  python3 - "$tmp/$key.txt" <<'PY'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
for k, name in enumerate(["prepare", "photons", "camera", "total"]):
    v = sorted(r[k] for r in rows)
    print(f"  {name:<8} min {v[0]:.3f}  median {statistics.median(v):.3f}")
PY
done
