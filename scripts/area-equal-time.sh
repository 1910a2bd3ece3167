#!/usr/bin/env bash
# Equal wall time on an area-lit scene against Mitsuba 3 (issue 46, "Must show"): renders the
# scene, in turn and REPEATS times (seeds 1..REPEATS), with bdpm's defaults (the file's
# settings), the file's settings in `balance` and `camis`, bdpm's `path`, and Mitsuba 3's
# `path` and `ptracer` (scripts/mitsuba-equal-time.py: the scene through `bdpm export`), each
# for SECONDS of render time at 2 threads, and compares each image with a long Mitsuba `path`
# reference (`bdpm compare`: rel. RMSE and relMSE of every pixel's luminance). Prints one line
# per render and the medians per configuration, also scaled to the budget (each render's time,
# its preparation included, is a little over it); run it alone on the machine (timings).
#   scripts/area-equal-time.sh [-o DIR] [--scene S.toml] [--seconds "20 60"] [--repeats N]
#                              [--resolution PX] [--reference REF.exr] [--reference-seconds S]
#                              [--configs "defaults balance camis path mitsuba-path mitsuba-ptracer"]
# Defaults: out/area-equal-time, scenes/cornell-box.toml, 20 s, 2 repeats, 256 px, all six
# configurations, a reference rendered first for 1200 s (Mitsuba `path`, unbiased: no merge
# radius in it). A scene Mitsuba cannot render as bdpm does (the Gaussian lobe's stand-in is
# another surface) takes a reference of bdpm's own `path` and --configs without mitsuba-*; the
# ratios are then to bdpm's `path`.
set -euo pipefail
abs() { case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac; }
out=out/area-equal-time scene=scenes/cornell-box.toml budgets=20 repeats=2 res=256 ref= ref_s=1200
configs="defaults balance camis path mitsuba-path mitsuba-ptracer"
while [ $# -gt 0 ]; do
  case "$1" in
    -o) out=$(abs "$2"); shift 2 ;;
    --scene) scene=$2; shift 2 ;;
    --seconds) budgets=$2; shift 2 ;;
    --repeats) repeats=$2; shift 2 ;;
    --resolution) res=$2; shift 2 ;;
    --reference) ref=$(abs "$2"); shift 2 ;;
    --reference-seconds) ref_s=$2; shift 2 ;;
    --configs) configs=$2; shift 2 ;;
    *) echo "area-equal-time.sh: unknown argument '$1' (see the comment at the top)" >&2; exit 2 ;;
  esac
done
case "${BDPM:-}" in */*) BDPM=$(abs "$BDPM") ;; esac
cd "$(dirname "$0")/.."
bdpm=${BDPM:-target/release/bdpm}
mkdir -p "$out"
if [ -z "$ref" ]; then
  ref=$out/reference.exr
  [ -f "$ref" ] || python3 scripts/mitsuba-equal-time.py "$scene" --seconds "$ref_s" \
    --integrator path --resolution "$res" --spp 16 --seed 1000 --bdpm "$bdpm" -o "$ref"
fi
score() { # IMAGE → "rel.RMSE relMSE" against the reference
  "$bdpm" compare "$1" "$ref" | grep "as reference" |
    sed -E 's/.*rel\. RMSE ([0-9.]+)%, relMSE ([0-9.e+-]+).*/\1 \2/'
}
for budget in $budgets; do
  log=$out/runs-$budget.txt
  : > "$log"
  for seed in $(seq 1 "$repeats"); do
    for config in $configs; do
      img=$out/$config-$budget-$seed.exr
      timed=(--time-budget "$budget" --threads 2 --seed "$seed" --passes 1000000
        --resolution "${res}x$res" --quiet -o "$img")
      case $config in
        defaults) "$bdpm" render "$scene" "${timed[@]}" 2> /dev/null ;;
        balance | camis | path)
          "$bdpm" render "$scene" --mode "$config" "${timed[@]}" 2> /dev/null ;;
        mitsuba-*) python3 scripts/mitsuba-equal-time.py "$scene" --seconds "$budget" \
          --integrator "${config#mitsuba-}" --resolution "$res" --seed "$seed" --bdpm "$bdpm" \
          -o "$img" > /dev/null ;;
      esac
      wall=$(python3 -c "import json, sys; t = json.load(open(sys.argv[1]))['timing'];
print('%.1f' % (t['prepare_s'] + t['render_s']))" "${img%.exr}.json")
      echo "$config $budget $seed $(score "$img") $wall" | tee -a "$log"
    done
  done
  python3 - "$log" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
budget = float(rows[0][1])
by = {}
for c, b, s, rmse, rel, wall in rows:
    # At the budget: a render's time (preparation and passes; the last pass ends past the
    # budget, a bdpm pass by up to a second) scaled out as a variance-dominated error falls,
    # rel. RMSE by √(wall/budget) and relMSE by wall/budget, as scripts/equal-time.sh does.
    k = float(wall) / budget
    by.setdefault(c, []).append((float(rmse), float(rel), float(wall), float(rmse) * k**0.5,
                                 float(rel) * k))
# The yardstick: Mitsuba's best, else bdpm's `path`, else none (e.g. --configs defaults alone).
peers = [c for c in by if c.startswith("mitsuba")] or [c for c in by if c == "path"]
med = lambda c, i: statistics.median(r[i] for r in by[c])
best = min(peers, key=lambda c: med(c, 0), default=None)
name = "Mitsuba's best" if peers != ["path"] else "bdpm's path"
print(f"budget {rows[0][1]} s, medians of {len(rows) // len(by)} runs; rel. RMSE in %:")
for c in by:
    print(f"  {c:16s} rel. RMSE {med(c, 0):.3f}  relMSE {med(c, 1):.3e}  wall {med(c, 2):.1f} s"
          + (f"  {med(c, 0) / med(best, 0):.2f}x {name}" if best else "")
          + f"; at the budget {med(c, 3):.3f}  {med(c, 4):.3e}"
          + (f"  {med(c, 3) / med(best, 3):.2f}x" if best else ""))
PY
done
