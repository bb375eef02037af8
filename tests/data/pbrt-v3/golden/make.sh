#!/usr/bin/env bash
# Regenerates the pbrt-v3 references of the per-pixel goldens (see README.md here). Only this script needs
# pbrt-v3; tests/golden.rs reads the PFMs it wrote.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
PBRT=${PBRT:-../shared/tools/pbrt-v3/pbrt}
refs=(
  # name|scene|Integrator line|pixel samples
  'ambientocclusion-spheres|spheres|Integrator "ambientocclusion" "integer nsamples" [16]|1024'
  'directlighting-spheres|spheres|Integrator "directlighting"|1024'
  'path-room|room|Integrator "path"|4096'
  # For the irradiance-cache golden's reference (indirect light = path with maxdepth 4 − directlighting):
  'directlighting-room|room|Integrator "directlighting"|1024'
  'path-maxdepth4-room|room|Integrator "path" "integer maxdepth" [4]|4096'
)
for r in "${refs[@]}"; do
  [ -n "${ONLY:-}" ] && [[ "$r" != $ONLY* ]] && continue
  IFS='|' read -r name scene integrator spp <<<"$r"
  # The golden's own settings (64×48, the scene's sampler and filter, the integrator's defaults) at many
  # more pixel samples; camera and world unchanged. Written next to the scene so relative paths resolve.
  tmp="scenes/.golden-$name.pbrt"
  sed -e 's/^Film .*/Film "image" "integer xresolution" [64] "integer yresolution" [48]/' \
      -e "s/\"integer pixelsamples\" \[[0-9]*\]/\"integer pixelsamples\" [$spp]/" \
      -e "s/^Integrator .*/$integrator/" \
      "scenes/$scene.pbrt" > "$tmp"
  "$PBRT" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "tests/data/pbrt-v3/golden/$name.pfm" "$tmp"
  rm "$tmp"
done
