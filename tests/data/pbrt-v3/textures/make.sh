#!/usr/bin/env bash
# Regenerates the texture test images and their pbrt-v3 references (see README.md here). Only this script
# needs pbrt-v3 and python3; tests/shading_textures.rs reads what it wrote.
#   <scene>-a.pfm: the scene as written (random sampler, 256 samples per pixel)
#   <scene>-b.pfm: the same with a stratified 16×16 jittered sampler (a second, independent estimate)
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
LOGDIR=${TMPDIR:-/tmp}
python3 make_images.py
# checker8.exr: pbrt-v3's own 8×8 half-float EXR rendering of checker-uv.pbrt, used as an image texture.
sed -e 's/^Film .*/Film "image" "integer xresolution" [8] "integer yresolution" [8]/' checker-uv.pbrt > .exr-source.pbrt
"$PBRT" --quiet --nthreads 1 --logdir "$LOGDIR" --outfile checker8.exr .exr-source.pbrt
rm .exr-source.pbrt
for f in *.pbrt; do
  scene=${f%.pbrt}
  "$PBRT" --quiet --nthreads 1 --logdir "$LOGDIR" --outfile "$scene-a.pfm" "$f"
  sed -e 's/^Sampler .*/Sampler "stratified" "integer xsamples" [16] "integer ysamples" [16]/' "$f" > ".$scene-b.pbrt"
  "$PBRT" --quiet --nthreads 1 --logdir "$LOGDIR" --outfile "$scene-b.pfm" ".$scene-b.pbrt"
  rm ".$scene-b.pbrt"
done
