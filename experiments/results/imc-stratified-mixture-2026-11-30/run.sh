#!/bin/bash
# STRATMIX=0/1 on sibenik and the Cornell box at 640x360, vgc+dgs, the equal-time spec's settings.
B=/work/main/target/release/cachert
R=/work/scratch/imc-et-wmix/runs
for scene in $SCENES; do
  if [ $scene = sib ]; then S=/work/shared/scenes/mcguire-sibenik-geometry/sibenik.pbrt; REF=$R/mcguire-sibenik-geometry-sibenik-importancecache-none-d6a0633a.exr; K=1400;
  else S=/work/shared/scenes/bitterli-cornell-box-v3/scene.pbrt; REF=$R/bitterli-cornell-box-v3-scene-importancecache-none-d6a0633a.exr; K=1400; fi
  for seed in $SEEDS; do for v in 0 1; do
    STRATMIX=$v $B render $S --integrator importancecache --placement vgc+dgs --caches $K --resolution 640x360 --seed $seed --nthreads 2 --set compensate=0 --set vpldepth=5 $EXTRA --stats /tmp/sm/st.json --outfile /tmp/sm/x.exr --quiet 2>/dev/null
    m=$($B compare /tmp/sm/x.exr $REF --metric rmse,flip,meandiff | tr '\n' ' ')
    rays=$(python3 -c "import json; s=json.load(open('/tmp/sm/st.json'))['stats']; print(s['render_rays']['occlusion'], round(s['times']['total'],2))")
    echo "$scene seed=$seed STRATMIX=$v $m rays,total_s=$rays"
  done; done
done
