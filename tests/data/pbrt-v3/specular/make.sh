#!/usr/bin/env bash
# Renders the pbrt-v3 references of the specular-chain scenes here (README.md). Only this script needs
# pbrt-v3; tests/specular_chains.rs reads the PFMs it writes. Run from anywhere.
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-../../../../../shared/tools/pbrt-v3/pbrt}
for scene in sun sky; do
  "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "$scene.pfm" "$scene.pbrt"
done
