#!/usr/bin/env bash
# The equal-time figures of docs/results.md ("Figures at equal time"): the Lambert and the
# glossy Cornell box, each rendered for the same time budget with the preprint's settings
# (scenes/preprint/), with the defaults (scenes/), and with the defaults but `balance`
# weights, then `bdpm figure` against a long `light` reference (independent seed), with
# Mitsuba's image as one more column when given.
#   scripts/figure-boxes.sh [-o DIR] [--budget S] [--reference-budget S] [--resolution WxH]
#                           [--mitsuba-lambert FILE.exr] [--mitsuba-glossy FILE.exr] [--mitsuba]
# --mitsuba renders the Lambert box's Mitsuba image itself, with Mitsuba 3's light tracer (`ptracer`,
# its better integrator for a point light in a closed box) for
# the same budget (scripts/mitsuba-equal-time.py); not the glossy box's, whose Gaussian lobe
# Mitsuba can only approximate (docs/scene-format.md, "Export to Mitsuba 3").
# Defaults: -o out/figure-boxes, 10 s per image, 180 s for the Lambert reference (4× that
# for the glossy one), 128x128 (whole seconds). Writes
# DIR/{lambert,glossy}/ with the renders (EXR, PNG, JSON reports) and figure.{png,html,json}.
set -euo pipefail
abs() { case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac; }
out=out/figure-boxes budget=10 ref_budget=180 res=128x128
mitsuba_lambert= mitsuba_glossy= render_mitsuba=
while [ $# -gt 0 ]; do
  case "$1" in
    -o) out=$(abs "$2"); shift 2 ;;
    --budget) budget=$2; shift 2 ;;
    --reference-budget) ref_budget=$2; shift 2 ;;
    --resolution) res=$2; shift 2 ;;
    --mitsuba-lambert) mitsuba_lambert=$(abs "$2"); shift 2 ;;
    --mitsuba-glossy) mitsuba_glossy=$(abs "$2"); shift 2 ;;
    --mitsuba) render_mitsuba=1; shift ;;
    *) echo "figure-boxes.sh: unknown argument '$1' (see the comment at the top)" >&2; exit 2 ;;
  esac
done
case "${BDPM:-}" in */*) BDPM=$(abs "$BDPM") ;; esac
cd "$(dirname "$0")/.."
bdpm=${BDPM:-target/release/bdpm}
# --passes is only the upper limit here: the time budget stops each render.
timed=(--resolution "$res" --passes 1000000 --quiet)
for box in lambert glossy; do
  d=$out/$box
  mkdir -p "$d"
  if [ "$box" = lambert ] && [ -n "$render_mitsuba" ] && [ -z "$mitsuba_lambert" ]; then
    python3 scripts/mitsuba-equal-time.py scenes/cornell-lambert.toml --seconds "$budget" \
      --integrator ptracer --resolution "${res%%x*}" --bdpm "$bdpm" -o "$d/mitsuba.exr"
    mitsuba_lambert=$d/mitsuba.exr
  fi
  # The glossy box's light-tracing reference converges slower (its sharp lobes): 4× the time.
  budget_ref=$([ "$box" = glossy ] && echo "$((4 * ref_budget))" || echo "$ref_budget")
  "$bdpm" render "scenes/cornell-$box.toml" --mode light --seed 1000003 \
    --time-budget "$budget_ref" "${timed[@]}" -o "$d/reference.exr"
  "$bdpm" render "scenes/preprint/cornell-$box.toml" --time-budget "$budget" "${timed[@]}" \
    -o "$d/preprint.exr"
  "$bdpm" render "scenes/cornell-$box.toml" --time-budget "$budget" "${timed[@]}" \
    -o "$d/defaults.exr"
  "$bdpm" render "scenes/cornell-$box.toml" --mode balance --time-budget "$budget" \
    "${timed[@]}" -o "$d/balance.exr"
  images=("$d/preprint.exr" "$d/defaults.exr" "$d/balance.exr")
  names="preprint settings,defaults,defaults + balance"
  mitsuba=$([ "$box" = lambert ] && echo "$mitsuba_lambert" || echo "$mitsuba_glossy")
  if [ -n "$mitsuba" ]; then
    images+=("$mitsuba")
    names="$names,Mitsuba 3"
  fi
  "$bdpm" figure --reference "$d/reference.exr" "${images[@]}" --names "$names" \
    --title "cornell-$box $res, $budget s per image" -o "$d"
done
