#!/usr/bin/env bash
# The stability sweeps of issue 13 (see README.md here), through `cachert experiment`. Renders go to
# $WORK (default /tmp/cachert-stability: the references are kept there and reused by later runs); each
# run's results.csv is copied here under runs/ and aggregate.py builds the CSVs from them.
#   results/stability/run.sh [map|sensitivity|apps]...      (default: all three)
set -euo pipefail
cd "$(dirname "$0")/../.."
B=${CACHERT:-target/release/cachert}
WORK=${WORK:-/tmp/cachert-stability}
S=../shared/scenes
OUT=results/stability/runs
mkdir -p "$OUT" "$WORK"
SCENES=(
  "sibenik|$S/mcguire-sibenik-geometry/sibenik.pbrt"
  "bathroom|$S/bitterli-bathroom/scene-v3.pbrt"
  "staircase2|$S/bitterli-staircase2/scene-v3.pbrt"
  "cornell|$S/bitterli-cornell-box-v3/scene.pbrt"
)
# The paper's cache densities (caches per pixel at 1920x1080): AO 120K, irradiance 40K, importance 25K.
density() { python3 -c "print(max(1, round($1 * $2 * $3 / (1920 * 1080) * $4)))"; }

run() { # tag integrator scene resolution caches placements seeds [--set k=v]...
  local tag=$1 integ=$2 scene=$3 res=$4 caches=$5 placements=$6 seeds=$7; shift 7
  local csv="$OUT/$tag.csv"
  [ -s "$csv" ] && { echo "skip $tag"; return; }
  local w="$WORK/$integ-$res"
  mkdir -p "$w"
  "$B" experiment --integrator "$integ" --scene "$scene" --resolution "$res" --caches "$caches" \
    --placements "$placements" --seeds "$seeds" --nthreads 2 --out "$w" "$@" > "$w/table.md"
  cp "$w/results.csv" "$csv"
  echo "done $tag"
}

# The map of where each placement loses to IM, with seed stability: cache AO, 4 scenes x 2 resolutions x
# half, once and twice the paper's density, the five placements, 8 seeds.
map() {
  for s in "${SCENES[@]}"; do IFS='|' read -r name file <<<"$s"
    for res in 160x90 320x180; do w=${res%x*}; h=${res#*x}
      c=$(for f in 0.5 1 2; do density 120000 $w $h $f; done | paste -sd,)
      run "map-cacheao-$name-$res" cacheao "$file" "$res" "$c" im,sd,sd+as,vgc,vgc+dgs 8
    done
  done
}

# SD's minimum cluster size and VGC's sigma_a (Fig. 8): cache AO at 320x180, the paper's density, 3 seeds.
sensitivity() {
  for s in "${SCENES[@]}"; do IFS='|' read -r name file <<<"$s"
    c=$(density 120000 320 180 1)
    for m in 1 5 10 50 100 1000; do
      run "sens-cacheao-$name-sd-$m" cacheao "$file" 320x180 "$c" sd 3 --set sdminsize=$m; done
    for a in 5 10 15 25 40 60; do
      run "sens-cacheao-$name-vgc-$a" cacheao "$file" 320x180 "$c" vgc 3 --set sigma_a=$a; done
  done
}

# The other applications at 160x90 (the QUICK settings of each, so references take minutes): the paper's
# density and twice it, 8 seeds, on the Cornell box and sibenik.
apps() {
  for s in "${SCENES[@]:0:1}" "${SCENES[@]:3:1}"; do IFS='|' read -r name file <<<"$s"
    c=$(for f in 1 2; do density 40000 160 90 $f; done | paste -sd,)
    run "map-irradiancecache-$name-160x90" irradiancecache "$file" 160x90 "$c" im,sd,sd+as,vgc,vgc+dgs 8 --set gather=16
    c=$(for f in 1 2; do density 25000 160 90 $f; done | paste -sd,)
    run "map-importancecache-$name-160x90" importancecache "$file" 160x90 "$c" im,sd,sd+as,vgc,vgc+dgs 8 --set vpls=1024
  done
}

for what in "${@:-map sensitivity apps}"; do
  for w in $what; do "$w"; done
done
