#!/usr/bin/env bash
# Renders every mode on both Cornell scenes at small settings, or compares two such sets bit
# for bit. Used to show that a performance change kept the image bits (docs/performance.md).
#   scripts/bit-check.sh render DIR          # with the current build (cargo build --release)
#   BDPM=/tmp/before/target/release/bdpm scripts/bit-check.sh render DIR   # another binary
#   scripts/bit-check.sh compare DIR_A DIR_B # exits non-zero if any image differs
set -euo pipefail
# Folders and BDPM given relative are the caller's: resolve them before moving to the
# repository root (where the scenes and the default binary are).
abs() { case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac; }
if [ "${1:-}" = render ] && [ $# -ge 2 ]; then set -- "$1" "$(abs "$2")"; fi
if [ "${1:-}" = compare ] && [ $# -ge 3 ]; then set -- "$1" "$(abs "$2")" "$(abs "$3")"; fi
# A bare command name is looked up on PATH as before; a path is the caller's.
case "${BDPM:-}" in */*) BDPM=$(abs "$BDPM") ;; esac
cd "$(dirname "$0")/.."
bin=${BDPM:-target/release/bdpm}
# `compare` needs a binary that has the compare command, i.e. this checkout's.
compare_bin=target/release/bdpm
# Every mode of the mode table, as the binary lists it (`bdpm modes`, hidden); a binary older
# than that command is answered for by this checkout's.
list_modes() {
  local m
  m=$("$bin" modes 2>/dev/null) || m=$("$compare_bin" modes 2>/dev/null) || m=
  [ -n "$m" ] && printf '%s\n' "$m"
}
case "${1:-}" in
  render)
    dir=${2:?usage: $0 render DIR}; mkdir -p "$dir"
    modes=$(list_modes) || { echo "cannot list the modes: build this checkout (cargo build --release)" >&2; exit 2; }
    for m in $modes; do
      "$bin" render scenes/preprint/cornell-lambert.toml --mode "$m" --resolution 64x64 --passes 2 \
        --photons 200000 --spp 4 -o "$dir/lambert-$m.exr" --quiet > /dev/null
      "$bin" render scenes/preprint/cornell-glossy.toml --mode "$m" --resolution 64x64 --passes 2 \
        --photons 100000 --spp 4 -o "$dir/glossy-$m.exr" --quiet > /dev/null
    done
    echo "rendered $(ls "$dir"/*.exr | wc -l) images into $dir" ;;
  compare)
    fail=0
    for f in "$2"/*.exr; do
      g="$3/$(basename "$f")"
      if out=$($compare_bin compare "$f" "$g" --require-identical); then
        echo "same bits: $(basename "$f")"
      else
        echo "DIFFERENT: $(basename "$f"): $out"; fail=1
      fi
    done
    exit $fail ;;
  *) echo "usage: $0 render DIR | compare DIR_A DIR_B" >&2; exit 2 ;;
esac
