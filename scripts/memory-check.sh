#!/usr/bin/env bash
# Measures the memory estimate against the peak resident memory (/usr/bin/time -v, maximum
# resident set size) for the scenes of round four (docs/robustness.md): a 10^6-triangle glTF
# mesh, one 4096^2 texture shown through 9 samplers, one 16384^2 texture; and how fast a render
# above --max-memory is refused (a 16384^2 forged PNG header under 200M, the mesh under 100M).
#   scripts/memory-check.sh                 # with this checkout's target/release/bdpm
#   BDPM=/path/to/bdpm scripts/memory-check.sh
#   SKIP_HUGE=1 scripts/memory-check.sh     # leave out the 16384^2 texture (0.8 GB, 5 s)
set -euo pipefail
abs() { case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac; }
case "${BDPM:-}" in */*) BDPM=$(abs "$BDPM") ;; esac
cd "$(dirname "$0")/.."
bin=${BDPM:-$PWD/target/release/bdpm}
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
gen() { python3 scripts/make-memory-scenes.py "$@" > /dev/null; }
gen mesh "$work/mesh" 1000000
gen texture "$work/t4096" 4096 9
gen texture "$work/forged" 16384 1 --forge
[ -n "${SKIP_HUGE:-}" ] || gen texture "$work/t16384" 16384 1

# measure NAME SCENE [ARGS...]: estimate and peak of a render that must succeed.
measure() {
  local name=$1 scene=$2; shift 2
  local out="$work/$name"
  /usr/bin/time -v "$bin" render "$scene" -o "$out.exr" --quiet "$@" > /dev/null 2> "$out.time"
  local rss_kb; rss_kb=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$out.time")
  python3 - "$out.json" "$rss_kb" "$name" <<'EOF'
import json, sys
report, rss_kb, name = json.load(open(sys.argv[1])), int(sys.argv[2]), sys.argv[3]
m = report["memory"]
est, peak = m["estimate_bytes"] / 2**20, rss_kb / 1024
items = ", ".join(f"{i['name']} {i['bytes'] / 2**20:.1f}" for i in m["items"] if i["bytes"] >= 2**20)
print(f"{name}: estimate {est:.1f} MiB, peak (max RSS) {peak:.1f} MiB, "
      f"estimate/peak {est / peak:.2f}; textures decoded {report['scene']['gltf']['textures']}; "
      f"items (MiB): {items}")
EOF
}

# refused NAME SCENE ARGS...: a render that must be refused; its time, peak and message.
refused() {
  local name=$1 scene=$2; shift 2
  local out="$work/$name"
  if /usr/bin/time -f "%e %M" -o "$out.time" "$bin" render "$scene" -o "$out.exr" --quiet "$@" \
      > /dev/null 2> "$out.err"; then
    echo "$name: NOT refused"; return 1
  fi
  # time writes "Command exited with non-zero status" first, then the format.
  read -r secs rss_kb < <(tail -n 1 "$out.time")
  echo "$name: refused in $secs s, peak $((rss_kb / 1024)) MiB: $(cat "$out.err")"
}

measure "mesh 10^6 triangles" "$work/mesh/mesh.toml"
measure "4096^2 texture, 9 samplers" "$work/t4096/texture.toml"
[ -n "${SKIP_HUGE:-}" ] || measure "16384^2 texture" "$work/t16384/texture.toml"
refused "forged 16384^2 PNG header, --max-memory 200M" "$work/forged/texture.toml" --max-memory 200M
refused "mesh 10^6 triangles, --max-memory 100M" "$work/mesh/mesh.toml" --max-memory 100M
