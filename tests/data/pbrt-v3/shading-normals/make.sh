#!/usr/bin/env bash
# Renders the pbrt-v3 reference of the shading-normal scene here (README.md). Only this script needs
# pbrt-v3; tests/importance_cache.rs reads the PFM it writes. Run from anywhere.
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
"$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile octahedron.pfm octahedron.pbrt
