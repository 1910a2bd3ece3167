#!/usr/bin/env bash
# The sweeps of docs/results.md, "Defaults that win at equal time": `bdpm study` runs radius,
# N_F, N_B and mode variants side by side (passes in turn) on the preprint's Cornell files with
# stratified samples, each for the same time, against the long references below. Usage:
#   scripts/equal-time-sweep.sh OUT_DIR [lambert-cpu|lambert-wall|glossy-wall|nothing-lambert|nothing-glossy]...
# The references (make them once; about 10 and 22 minutes on 2 cores; own error 0.54 % and 2.7 %):
#   bdpm render scenes/preprint/cornell-lambert.toml --mode light --sampler stratified --spp 60 --passes 1000 --seed 4243 -o out/ref/lambert-light-1000.exr
#   bdpm render scenes/preprint/cornell-glossy.toml --mode path --sampler stratified --passes 4800 --seed 4244 -o out/ref/glossy-path-4800.exr
# The sweeps in docs/results.md ran against earlier, coarser ones (own error 1.5 % and 8 %):
#   bdpm render scenes/preprint/cornell-lambert.toml --mode light --passes 400 --seed 4242 -o out/ref/lambert-light-400.exr
#   bdpm render scenes/preprint/cornell-glossy.toml --mode path --passes 600 --seed 4243 -o out/ref/glossy-path-600.exr
# (LAMBERT_REF=… GLOSSY_REF=… to use those).
set -euo pipefail
out=$1; shift
bin=${BDPM:-$(cd "$(dirname "$0")/.." && pwd)/target/release/bdpm}
L=${LAMBERT_REF:-out/ref/lambert-light-1000.exr}
G=${GLOSSY_REF:-out/ref/glossy-path-4800.exr}
base="balance:sampler=independent"   # the preprint's layout: the scene file's own radius
mkdir -p "$out"
[ $# -gt 0 ] || set -- lambert-cpu lambert-wall glossy-wall
for what in "$@"; do
  case $what in
    lambert-cpu)
      # 30 s of CPU time per variant (steadier than wall time on a shared machine).
      "$bin" study scenes/preprint/cornell-lambert.toml --sampler stratified --time-budget 30 --clock cpu \
        --modes "$base,balance,balance:radius=0.25px,balance:radius=0.35px:photons=500000,balance:radius=0.5px:photons=250000,balance:radius=0.5px:photons=500000:spp=16,balance:radius=1px:photons=100000:spp=16,balance:radius=1px:photons=100000:spp=4,balance:radius=2px:photons=30000:spp=4,balance:radius=0.2px:photons=2000000,optimal-path:radius=0.25px,optimal-path:radius=0.2px:photons=2000000,optimal-path:radius=0.15px:photons=2000000,camis:radius=0.25px,light" \
        --reference "$L" --quiet -o "$out/lambert-cpu" ;;
    lambert-wall)
      # 20 s of wall time per variant, the must-show's clock.
      "$bin" study scenes/preprint/cornell-lambert.toml --sampler stratified --time-budget 20 --clock wall \
        --modes "$base,balance:radius=0.25px,optimal-path:radius=0.25px,balance:radius=0.2px:photons=2000000,optimal-path:radius=0.2px:photons=2000000,camis:radius=0.2px:photons=2000000,balance:radius=0.15px:photons=2000000,balance:radius=0.2px:photons=2000000:spp=40" \
        --reference "$L" --quiet -o "$out/lambert-wall" ;;
    glossy-wall)
      "$bin" study scenes/preprint/cornell-glossy.toml --sampler stratified --time-budget 20 --clock wall \
        --modes "$base,balance,balance:radius=0.25px,balance:radius=0.5px,balance:radius=1px,balance:radius=0.5px:photons=1000000,optimal-path:radius=0.5px,optimal-path:radius=1px,camis:radius=0.5px" \
        --reference "$G" --quiet -o "$out/glossy-wall" ;;
    nothing-lambert|nothing-glossy)
      # A scene that sets nothing: the Cornell file without its [render] table, the first
      # variant the library's defaults, the others candidates for them; 30 s of CPU time each.
      box=${what#nothing-}
      sed '/^\[render\]/,/^\[camera\]/{/^\[camera\]/!d}' "scenes/cornell-$box.toml" > "$out/$what.toml"
      ref=$L; [ "$box" = glossy ] && ref=$G
      "$bin" study "$out/$what.toml" --time-budget 30 --clock cpu \
        --modes "balance:radius=0.0017475:photons=100000:spp=4,optimal-path:radius=0.25px:photons=1000000:spp=16,optimal-path:radius=0.3px:photons=1000000:spp=30,optimal-path,optimal-path:radius=0.2px:photons=2000000:spp=30,optimal-path:radius=0.35px:photons=500000:spp=16" \
        --reference "$ref" --quiet -o "$out/$what" ;;
    *) echo "equal-time-sweep.sh: unknown sweep $what" >&2; exit 2 ;;
  esac
  echo "$out/$what/study.md"
done
