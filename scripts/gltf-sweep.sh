#!/usr/bin/env bash
# Renders every .gltf and .glb file under a folder (default: Debian's assimp-testmodels,
# /usr/share/assimp/models) at 8x8 pixels, one pass, under a memory limit, and counts how
# each ended: rendered, refused with one error line, or panicked (exit 101) / aborted (134,
# or killed by any signal). Exits non-zero if any panicked or aborted (docs/robustness.md,
# round four).
#   scripts/gltf-sweep.sh [DIR]            # with this checkout's target/release/bdpm
#   BDPM=/path/to/bdpm scripts/gltf-sweep.sh [DIR]
#   VERBOSE=1 scripts/gltf-sweep.sh        # also print each file's outcome and message
set -uo pipefail
abs() { case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac; }
root=$(abs "${1:-/usr/share/assimp/models}")
case "${BDPM:-}" in */*) BDPM=$(abs "$BDPM") ;; esac
cd "$(dirname "$0")/.."
bin=${BDPM:-$PWD/target/release/bdpm}
[ -d "$root" ] || { echo "no folder $root (apt-get install assimp-testmodels)"; exit 2; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
ok=0; refused=0; bad=0; other=0; total=0
while IFS= read -r -d '' f; do
  total=$((total + 1))
  # A TOML basic string: backslashes and quotes escaped.
  esc=$(printf %s "$f" | sed 's/\\/\\\\/g; s/"/\\"/g')
  cat > "$work/scene.toml" <<EOF
[render]
resolution = [8, 8]
passes = 1
spp = 1
mode = "path"
[camera]
position = [0.0, 0.0, -5.0]
look_at = [0.0, 0.0, 0.0]
vfov = 60
[[light]]
position = [0.0, 0.0, -3.0]
flux = 1.0
[[shape]]
type = "mesh"
file = "$esc"
EOF
  "$bin" render "$work/scene.toml" -o "$work/out.exr" --quiet --max-memory 2G \
    > "$work/stdout" 2> "$work/stderr"
  rc=$?
  lines=$(wc -l < "$work/stderr")
  case $rc in
    0) ok=$((ok + 1)); what=rendered ;;
    1) if [ "$lines" -eq 1 ]; then refused=$((refused + 1)); what=refused
       else other=$((other + 1)); what="exit 1 with $lines error lines"; fi ;;
    101|134|13[0-9]|14[0-9]) bad=$((bad + 1)); what="PANIC/ABORT (exit $rc)" ;;
    *) other=$((other + 1)); what="exit $rc" ;;
  esac
  case $what in rendered|refused) [ -n "${VERBOSE:-}" ] || continue ;; esac
  echo "$what: ${f#"$root"/}: $(head -c 300 "$work/stderr")"
done < <(find "$root" -type f \( -iname '*.gltf' -o -iname '*.glb' \) -print0 | sort -z)
echo "$total files under $root: $ok rendered, $refused refused with one line, $bad panicked or aborted, $other other"
[ "$bad" -eq 0 ] && [ "$other" -eq 0 ]
