#!/usr/bin/env bash
# The memory estimates of the lab commands against the measured peak resident memory
# (`/usr/bin/time -v`, "Maximum resident set size"), docs/robustness.md, round four:
#   study   a study of 4 entries on the Lambert box at 256², 10⁶ photons per pass, 2 passes,
#           with the reference it renders first (32 passes of `light`); its estimate is the
#           larger of the reference render's and the modes' held together (the Memory line of
#           the study's report).
#   merge   a merge of 45 partial renders of one pass each (balance, 256², 10⁵ photons; each
#           part from `render --first-pass K --passes 1`), estimate from the merge's report.
# Usage: scripts/memory-check-lab.sh [OUT_DIR] [study|merge]...   (default: out/memory-lab, both)
# Prints one line per case: estimate, measured peak and their ratio.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BDPM:-$root/target/release/bdpm}
out=${1:-out/memory-lab}
shift || true
[ $# -gt 0 ] || set -- study merge
mkdir -p "$out"
scene=$root/scenes/cornell-lambert.toml

# Maximum resident set size of the command's log of /usr/bin/time -v, in bytes.
peak() { awk -F': ' '/Maximum resident set size/ { print $2 * 1024 }' "$1"; }
# "12.5 MiB" and the like as bytes.
bytes() {
  python3 -c 'import sys; v, u = sys.argv[1], sys.argv[2]
print(int(float(v) * {"KiB": 1 << 10, "MiB": 1 << 20, "GiB": 1 << 30, "TiB": 1 << 40}[u]))' "$1" "$2"
}
say() { # CASE ESTIMATE PEAK
  python3 -c 'import sys; c, e, p = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
print(f"{c}: estimate {e / 1e6:.1f} MB, measured peak {p / 1e6:.1f} MB, estimate/peak {e / p:.2f}")' "$@"
}

for what in "$@"; do
  case $what in
    study)
      dir=$out/study4
      rm -rf "$dir"
      /usr/bin/time -v "$bin" study "$scene" --modes balance,optimal,optimal-path,corrected-balance \
        --resolution 256x256 --passes 2 --photons 1000000 --spp 4 --quiet -o "$dir" \
        > "$dir.log" 2> "$dir.time"
      line=$(grep '^Memory: ' "$dir/study.md")
      modes=$(sed -E 's/.*held together were estimated at ([0-9.]+) ([KMGT]iB).*/\1 \2/' <<< "$line")
      ref=$(sed -nE 's/.*reference render before them at ([0-9.]+) ([KMGT]iB).*/\1 \2/p' <<< "$line")
      e=$(bytes $modes)
      if [ -n "$ref" ]; then r=$(bytes $ref); [ "$r" -gt "$e" ] && e=$r; fi
      say "study of 4 entries (study.md: $line)" "$e" "$(peak "$dir.time")"
      ;;
    merge)
      dir=$out/merge45
      rm -rf "$dir"; mkdir -p "$dir"
      parts=()
      for k in $(seq 0 44); do
        "$bin" render "$scene" --mode balance --resolution 256x256 --photons 100000 --spp 1 \
          --first-pass "$k" --passes 1 --quiet -o "$dir/part$k.exr" > /dev/null
        parts+=("$dir/part$k.accum.exr")
      done
      /usr/bin/time -v "$bin" merge "${parts[@]}" --quiet -o "$dir/merged.exr" \
        > "$dir.log" 2> "$dir.time"
      e=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["memory"]["estimate_bytes"])' "$dir/merged.json")
      say "merge of 45 one-pass parts" "$e" "$(peak "$dir.time")"
      ;;
    *) echo "unknown case: $what (study or merge)" >&2; exit 2 ;;
  esac
done
