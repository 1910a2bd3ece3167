#!/usr/bin/env bash
# The sampler's figures of docs/results.md ("Stratified camera samples"): for each Cornell scene,
# resolution and radius, one `bdpm study` that runs `balance` and `optimal-path` with independent
# and with stratified samples side by side (round-robin passes, CPU clock), against the study's
# cached `light` reference. Usage:
#   scripts/sampler-study.sh OUT_DIR [PASSES] [RESOLUTIONS] [RADII]
# e.g. scripts/sampler-study.sh out/sampler 6 "128 256 512" "scene 0.01"
# ("scene" = the scene file's radius, box/1600 = 1.75 mm). Prints one summary line per study.
set -euo pipefail
out=$1; passes=${2:-6}; resolutions=${3:-"128 256 512"}; radii=${4:-"scene 0.01"}
bin=${BDPM:-$(cd "$(dirname "$0")/.." && pwd)/target/release/bdpm}
mkdir -p "$out"
for scene in cornell-lambert cornell-glossy; do
  for res in $resolutions; do
    ref=()
    for r in $radii; do
      modes="balance:sampler=independent,balance:sampler=stratified,optimal-path:sampler=independent,optimal-path:sampler=stratified"
      extra=()
      [ "$r" != scene ] && extra=(--radius "$r")
      dir="$out/$scene-$res-r$r"
      # The reference: 64 passes of `light`, rendered by the first radius's study and cached
      # in its directory (its own error is in study.md); `light` merges nothing, so the
      # other radii read it.
      "$bin" study "scenes/preprint/$scene.toml" --modes "$modes" --passes "$passes" \
        --resolution "${res}x${res}" "${extra[@]}" --clock cpu --quiet \
        --reference-passes 64 "${ref[@]}" -o "$dir" > "$dir.log"
      [ ${#ref[@]} -gt 0 ] || ref=(--reference "$(ls "$dir"/reference-*.exr)")
      echo "$dir/study.md"
    done
  done
done
