#!/bin/bash
# sibenik 640x360: importance caching with more of C's draws against the defaults and uniform sampling
cd /work/scratch/c2
B=/work/main/target/release/cachert; S=/work/shared/scenes/mcguire-sibenik-geometry/sibenik.pbrt
C=/work/main/experiments/results/imc-profile-2026-11-29/concentration.py
[ -f ref.pfm ] || $B convert ref.exr ref.pfm > /dev/null
echo "# sibenik 640x360, compensate 0, vpldepth 5, 2 threads, against placement none (seed 0) at the same size"
for v in "cache:1400:" "cache:1400:distributions=fubc2g" "cache:1400:distributions=fubc4g" "uniform:0:draws=64" "uniform:0:draws=128"; do
  IFS=: read mode caches extra <<< "$v"
  for seed in 0 1 2; do
    args="--set sampling=$mode"; [ -n "$extra" ] && args="$args --set $extra"
    pl="--placement vgc+dgs --caches $caches"; [ $mode = uniform ] && pl="--placement vgc+dgs --caches 1400"
    $B render $S --integrator importancecache $pl --resolution 640x360 --seed $seed --nthreads 2 --set compensate=0 --set vpldepth=5 $args --stats t.json --outfile t.exr --quiet 2>/dev/null
    $B convert t.exr t.pfm > /dev/null
    tt=$(python3 -c "import json;d=json.load(open('t.json'))['stats'];print('total_s', round(d['times']['total'],2), 'render_rays', d['render_rays']['total'])")
    echo "sampling=$mode $extra seed=$seed $tt"; python3 $C t.pfm ref.pfm | sed 's/^/    /'
  done
done
