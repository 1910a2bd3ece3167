#!/usr/bin/env bash
# Would choosing per image region pay? Studies of variants side by side whose report ends with
# the regional-choice paragraph (`bdpm study`: per 8×8 block the variant with the least relV at
# its time, in sample and cross-validated between even and odd passes). docs/results.md,
# "Choosing per region: a per-pixel radius or light-tracing share, bounded".
# Usage: scripts/regional-study.sh OUT_DIR [lambert-radius|glossy-radius|lambert-technique|glossy-technique|lambert-lt-share|glossy-lt-share]...
# The *-lt-share studies scale light tracing's density ratio by k = pixel_table_rays/16 (the
# scale has no setting of its own): they need a binary built with
# docs/results/lt-share-scale.patch applied (`git apply` it in a scratch worktree, build, and
# point BDPM at that binary). References as in scripts/equal-time-sweep.sh.
set -euo pipefail
out=$1; shift
bin=${BDPM:-$(cd "$(dirname "$0")/.." && pwd)/target/release/bdpm}
L=${LAMBERT_REF:-out/ref/lambert-light-1000.exr}
G=${GLOSSY_REF:-out/ref/glossy-path-4800.exr}
# The glossy studies ran before scenes/cornell-glossy.toml set adaptive_radius: they keep one
# radius, as measured.
study() { # NAME SCENE REF MODES [FLAGS...]
  "$bin" study "$2" --modes "$4" --time-budget 40 --clock cpu --reference "$3" --quiet -o "$out/$1" "${@:5}"
}
one="--adaptive-radius false"
lt="balance:light_tracing=true"
for what in "$@"; do
  case $what in
    lambert-radius) study "$what" scenes/cornell-lambert.toml "$L" \
      "optimal-path:radius=0.1px,optimal-path,optimal-path:radius=0.3px,optimal-path:radius=0.5px,optimal-path:radius=0.8px" ;;
    glossy-radius) study "$what" scenes/cornell-glossy.toml "$G" \
      "optimal-path:radius=0.25px,optimal-path:radius=0.35px,optimal-path,optimal-path:radius=0.7px,optimal-path:radius=1px" $one ;;
    lambert-technique) study "$what" scenes/cornell-lambert.toml "$L" \
      "balance,optimal-path,$lt,optimal-path:light_tracing=true" ;;
    glossy-technique) study "$what" scenes/cornell-glossy.toml "$G" \
      "balance,optimal-path,$lt,optimal-path:light_tracing=true" $one ;;
    lambert-lt-share) study "$what" scenes/cornell-lambert.toml "$L" \
      "$lt:pixel_table_rays=8,$lt:pixel_table_rays=16,$lt:pixel_table_rays=32,$lt:pixel_table_rays=48" ;;
    glossy-lt-share) study "$what" scenes/cornell-glossy.toml "$G" \
      "$lt:pixel_table_rays=8,$lt:pixel_table_rays=16,$lt:pixel_table_rays=32,$lt:pixel_table_rays=64" $one ;;
    *) echo "unknown study: $what" >&2; exit 2 ;;
  esac
done
