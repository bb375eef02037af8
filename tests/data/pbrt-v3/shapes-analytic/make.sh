#!/usr/bin/env bash
# Regenerates the pbrt-v3 references of the scenes here (see README.md). Only this script needs pbrt-v3;
# tests/shapes_analytic.rs reads the PFMs it writes.
#
# Each scene file carries reference b's render options (stratified 4×4 sampler, box filter); reference a
# is the same file with the Sampler line replaced by a random sampler with 16 pixel samples.
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
for scene in ${SCENES:-quadrics curves instanced}; do
  for variant in a b; do
    if [ "$variant" = a ]; then
      sed -e 's/^Sampler .*/Sampler "random" "integer pixelsamples" [16]/' "$scene.pbrt" > ".$scene-$variant.pbrt"
    else
      cp "$scene.pbrt" ".$scene-$variant.pbrt"
    fi
    "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "$scene-$variant.pfm" ".$scene-$variant.pbrt"
    rm ".$scene-$variant.pbrt"
  done
done
