#!/usr/bin/env bash
# The cache integrators on real scenes against pbrt-v3 `path` (issue 41): for each scene, pbrt-v3 renders a
# small reference (`path`, maxdepth 5, 256 random samples per pixel, box filter; camera and world unchanged)
# and cachert renders importance caching (vgc+dgs at its default budget, and `none`, the exact VPL sum) and
# irradiance caching (`output full`) at the same size, with the reference's light paths; `cachert compare` scores each against the reference.
# Prints a Markdown table (results.md). Run from the repository root after `cargo build --release`:
#   bash experiments/results/i41-real-scenes/run.sh > experiments/results/i41-real-scenes/results.md
# $CACHERT picks another binary (e.g. an older build, for a before/after); references and images go to
# $OUT (default /tmp/cachert-i41-real); an existing reference is reused. Skipped when ../shared is absent.
set -euo pipefail
S=../shared/scenes
V3=../shared/tools/pbrt-v3/pbrt
C=${CACHERT:-target/release/cachert}
OUT=${OUT:-/tmp/cachert-i41-real}
for f in "$S" "$V3"; do [ -e "$f" ] || { echo "skipped: $f is absent" >&2; exit 0; }; done
mkdir -p "$OUT"
# name, scene file, width, height
SCENES="veach-mis pbrtv3scenes-veach-mis/mis.pbrt 96 72
staircase2 bitterli-staircase2/scene-v3.pbrt 96 96
bathroom bitterli-bathroom/scene-v3.pbrt 96 96
buddha pbrtv3scenes-buddha-fractal/ao-ref.pbrt 60 96
cornell bitterli-cornell-box-v3/scene.pbrt 96 96"
echo "| scene | integrator | mean vs pbrt-v3 | RMSE | HDR-FLIP | cachert s |"
echo "|---|---|---|---|---|---|"
while read -r name file w h; do
  ref="$OUT/$name-v3.pfm"
  if [ ! -e "$ref" ]; then
    # Written next to the scene so that its relative paths resolve; removed after.
    tmp="$S/$(dirname "$file")/.i41-ref-$name.pbrt"
    sed -e "s/^Film .*/Film \"image\" \"integer xresolution\" [$w] \"integer yresolution\" [$h]/" \
        -e 's/^Sampler .*/Sampler "random" "integer pixelsamples" [256]/' \
        -e 's/^PixelFilter .*/PixelFilter "box"/' \
        -e 's/^Integrator .*/Integrator "path" "integer maxdepth" [5]/' "$S/$file" > "$tmp"
    grep -q '^Integrator' "$tmp" || sed -i '1i Integrator "path" "integer maxdepth" [5]' "$tmp"
    "$V3" --quiet --nthreads 2 --logdir "${TMPDIR:-/tmp}" --outfile "$ref" "$tmp" > /dev/null 2>&1 || true
    rm -f "$tmp"
  fi
  [ -e "$ref" ] || { echo "| $name | pbrt-v3 failed | | | | |"; continue; }
  # The light paths of the reference's maxdepth 5 (the scenes' own lines say 1, 17 or 65, which a cache render
  # that replaces them would take): vpldepth 4 and irradiance caching's maxdepth 4.
  for run in "importancecache placement=vgc+dgs vpldepth=4" "importancecache placement=none vpldepth=4" \
             "irradiancecache output=full maxdepth=4"; do
    set -- $run
    img="$OUT/$name-$1-${2//[=+]/_}.pfm"
    start=$(date +%s.%N)
    "$C" render --quiet --nthreads 2 --resolution "${w}x$h" --integrator "$1" --set "$2" --set "$3" --outfile "$img" "$S/$file" 2> /dev/null
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    read -r md rmse flip <<< "$("$C" compare --metric meandiff,rmse,flip "$img" "$ref" | awk '{print $2}' | tr '\n' ' ')"
    awk -v n="$name" -v i="$1 $2" -v md="$md" -v r="$rmse" -v f="$flip" -v s="$secs" \
      'BEGIN { printf "| %s | %s | %+.2f %% | %.4f | %.4f | %.1f |\n", n, i, 100 * md, r, f, s }'
  done
done <<< "$SCENES"
