#!/usr/bin/env bash
# Regenerates the pbrt-v3 references of the light tests (tests/shading_lights.rs; see README.md here).
# Only this script needs pbrt-v3 (and python3 for the environment map); the tests read what it wrote.
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
python3 envmap.py envmap.pfm
for scene in envmap emitters delta; do
  "$PBRT" --quiet --nthreads 1 --logdir "${TMPDIR:-/tmp}" --outfile "$scene-ref.pfm" "$scene.pbrt"
done
# Area lights: a pair of noisy renders (a: random 64 spp, b: stratified 8×8 jittered), the
# assert_matches_pbrt_pair convention of tests/common.
for variant in a b; do
  if [ "$variant" = a ]; then
    sampler='Sampler "random" "integer pixelsamples" [64]'
  else
    sampler='Sampler "stratified" "integer xsamples" [8] "integer ysamples" [8]'
  fi
  sed -e "s/^Sampler .*/$sampler/" area.pbrt > .area-$variant.pbrt
  "$PBRT" --quiet --nthreads 1 --logdir "${TMPDIR:-/tmp}" --outfile "area-$variant.pfm" ".area-$variant.pbrt"
  rm .area-$variant.pbrt
done
