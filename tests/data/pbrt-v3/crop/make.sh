#!/usr/bin/env bash
# Renders pbrt-v3's cropped EXR of plane.pbrt here (README.md): --cropwindow 0.25 0.75 0.25 1 of the 8×8
# film. Only this script needs pbrt-v3; tests/first_hour.rs reads the EXR it writes. Run from anywhere.
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
"$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --cropwindow 0.25 0.75 0.25 1 --outfile crop.exr plane.pbrt
