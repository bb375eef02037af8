#!/usr/bin/env bash
# Regenerates the pbrt-v3 references of the shipped scenes (see README.md here). Only this script needs
# pbrt-v3; the tests read the PFMs it wrote.
set -euo pipefail
cd "$(dirname "$0")/../../.."
PBRT=${PBRT:-../shared/tools/pbrt-v3/pbrt}
for scene in spheres room; do
  for variant in a b; do
    if [ "$variant" = a ]; then
      sampler='Sampler "random" "integer pixelsamples" [16]'
    else
      sampler='Sampler "stratified" "integer xsamples" [4] "integer ysamples" [4]'
    fi
    # The same substitutions as tests/shipped_scenes.rs: small film, box filter, 16 pixel samples,
    # 64 AO rays; camera and world unchanged. Written next to the scene so relative paths resolve.
    tmp="scenes/.$scene-ref-$variant.pbrt"
    sed -e 's/^Film .*/Film "image" "integer xresolution" [64] "integer yresolution" [48]/' \
        -e "s/^Sampler .*/$sampler/" \
        -e 's/^PixelFilter .*/PixelFilter "box"/' \
        -e 's/"integer nsamples" \[16\]/"integer nsamples" [64]/' \
        "scenes/$scene.pbrt" > "$tmp"
    "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "tests/data/pbrt-v3/$scene-$variant.pfm" "$tmp"
    rm "$tmp"
  done
done
