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
