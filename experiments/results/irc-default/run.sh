#!/usr/bin/env bash
# irradiancecache's default (32x32 paths per cache, three times the paper's budget) against the paper's setting
# (64x64 paths, the paper's budget) on sibenik at 240x135, error against cachert's own `path` (maxdepth 5, the
# light paths of irradiancecache's output full at maxdepth 4) at 512 samples per pixel. From the repository root,
# with the shared scenes at ../shared; about 5 min on 2 cores. Prints one line per render.
set -euo pipefail
bin=${CACHERT:-target/release/cachert}
bin=$(realpath "$bin")
scene=$(realpath ../shared/scenes/mcguire-sibenik-geometry)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ln -s "$scene/sibenik-converted.obj" "$work/"
res='s/"integer xresolution" \[480\] "integer yresolution" \[270\]/"integer xresolution" [240] "integer yresolution" [135]/'
sed "s/^Integrator .*/Integrator \"path\" \"integer maxdepth\" [5]/; $res" "$scene/sibenik.pbrt" > "$work/path.pbrt"
sed "s/^Integrator .*/Integrator \"irradiancecache\" \"string output\" \"full\" \"integer maxdepth\" [4]/; $res" \
  "$scene/sibenik.pbrt" > "$work/irc.pbrt"
"$bin" render "$work/path.pbrt" --spp 512 --outfile "$work/ref.pfm" --quiet
run() { # name, seed, flags...
  local name=$1 seed=$2; shift 2
  local t0 t1
  t0=$(awk '{print $14+$15+$16+$17}' /proc/$$/stat)
  /usr/bin/time -f "%U %S" -o "$work/time" "$bin" render "$work/irc.pbrt" --placement vgc+dgs --seed "$seed" "$@" \
    --stats "$work/stats.json" --outfile "$work/$name.pfm" --quiet
  local cpu caches errs
  cpu=$(awk '{printf "%.2f", $1 + $2}' "$work/time")
  caches=$(grep -o '"total_caches": *[0-9]*' "$work/stats.json" | grep -o '[0-9]*$')
  errs=$("$bin" compare "$work/$name.pfm" "$work/ref.pfm" --metric rmse,flip | awk '{printf "%s %s ", $1, $2}')
  echo "$name seed $seed caches $caches cpu_s $cpu $errs"
}
for seed in 0 1 2; do
  run paper-64x64 "$seed" --set gather=64 --caches 625
  run default "$seed"
  run 16x16-6x "$seed" --set gather=16 --caches 3750
done
