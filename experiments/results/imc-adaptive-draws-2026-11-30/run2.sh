#!/bin/bash
# Usage: SCENES="sib cor" SEEDS="0" VARIANTS="ADAPT=0 ADAPT=4" EXTRA="" run2.sh
B=/work/main/target/release/cachert
R=/work/scratch/imc-et-wmix/runs
for scene in $SCENES; do
  if [ $scene = sib ]; then S=/work/shared/scenes/mcguire-sibenik-geometry/sibenik.pbrt; REF=$R/mcguire-sibenik-geometry-sibenik-importancecache-none-d6a0633a.exr;
  elif [ $scene = bath ]; then S=/work/shared/scenes/bitterli-bathroom/scene-v3.pbrt; REF=$R/bitterli-bathroom-scene-v3-importancecache-none-d6a0633a.exr;
  else S=/work/shared/scenes/bitterli-cornell-box-v3/scene.pbrt; REF=$R/bitterli-cornell-box-v3-scene-importancecache-none-d6a0633a.exr; fi
  K=${CACHES:-1400}
  for seed in $SEEDS; do for v in $VARIANTS; do
    env $(echo $v | tr "," " ") $B render $S --integrator importancecache --placement vgc+dgs --caches $K --resolution 640x360 --seed $seed --nthreads 2 --set compensate=0 --set vpldepth=5 $EXTRA --stats /tmp/sm/st.json --outfile /tmp/sm/x.exr --quiet 2>/tmp/sm/err.txt
    m=$($B compare /tmp/sm/x.exr $REF --metric rmse,flip,meandiff | tr '\n' ' ')
    rays=$(python3 -c "import json; s=json.load(open('/tmp/sm/st.json'))['stats']; print(s['render_rays']['occlusion'], round(s['times']['render'],2), round(s['times']['total'],2))")
    echo "$scene K=$K seed=$seed $v $m rays,render_s,total_s=$rays $(grep adapt /tmp/sm/err.txt)"
  done; done
done
