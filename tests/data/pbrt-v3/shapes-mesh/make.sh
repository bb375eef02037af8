#!/usr/bin/env bash
# Regenerates the pbrt-v3 references of the mesh-producing shapes (see README.md here). Only this script
# needs pbrt-v3; tests/shapes_mesh.rs reads the PFMs it wrote.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here"
PBRT=${PBRT:-$here/../../../../../shared/tools/pbrt-v3/pbrt}
for scene in loopsubdiv-closed loopsubdiv-open heightfield nurbs; do
  # b: the scene as written (stratified 4x4), which is what cachert renders in the test.
  "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "$scene-b.pfm" "$scene.pbrt"
  # a: the same with pbrt-v3's random sampler, 16 samples per pixel.
  tmp=".$scene-ref-a.pbrt"
  sed -e 's/^Sampler .*/Sampler "random" "integer pixelsamples" [16]/' "$scene.pbrt" > "$tmp"
  "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "$scene-a.pfm" "$tmp"
  rm "$tmp"
done
