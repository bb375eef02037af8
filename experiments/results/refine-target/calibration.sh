#!/bin/bash
# How calibration.csv was made (2026-11-28): cache AO at 160x90, seed 0, the per-sample reference and refine
# with a target it never meets (0.0001) at ceilings of 64-4000 caches; achieved = RMSE / mean of the reference
# over all channels, estimate_committed = refine's last estimate (--stats error_estimates), estimate_kappa1 = it
# over sqrt(KAPPA) of the binary that ran. Run from the repository root after `cargo build --release`:
#   bash experiments/results/refine-target/calibration.sh SCRATCH_DIR    # writes SCRATCH_DIR/calibration.csv
set -e
ROOT=$(pwd)
R=$ROOT/target/release/cachert
SHARED=$ROOT/../shared
mkdir -p "$1" && cd "$1"
declare -A S=(
  [veach-mis]=$SHARED/scenes/pbrtv3scenes-veach-mis/mis.pbrt
  [room]=$ROOT/scenes/room.pbrt
  [spheres]=$ROOT/scenes/spheres.pbrt
  [sibenik]=$SHARED/scenes/mcguire-sibenik-geometry/sibenik.pbrt
  [bathroom]=$SHARED/scenes/bitterli-bathroom/scene-v3.pbrt
  [staircase2]=$SHARED/scenes/bitterli-staircase2/scene-v3.pbrt
  [cornell-box]=$SHARED/scenes/bitterli-cornell-box-v3/scene.pbrt
)
echo "scene,set,caches,achieved,estimate_kappa1,estimate_committed" > calibration.csv
for name in sibenik bathroom staircase2 cornell-box veach-mis room spheres; do
  case $name in veach-mis|room|spheres) set=calibration;; *) set=stability;; esac
  f=${S[$name]}
  $R render $f --integrator cacheao --placement none --resolution 160x90 --outfile ref-$name.exr --quiet 2>/dev/null
  $R convert ref-$name.exr ref-$name.pfm >/dev/null 2>&1
  for n in 64 250 1000 4000; do
    $R render $f --integrator cacheao --placement refine --caches $n --target-error 0.0001 --resolution 160x90 --outfile r-$name-$n.exr --stats r-$name-$n.json --quiet 2>/dev/null
    rmse=$($R compare r-$name-$n.exr ref-$name.exr --metric rmse | awk '{print $2}')
    python3 - "$name" "$set" "$n" "$rmse" "$ROOT" <<'PY'
import json, sys, math
import re
# The constant of the binary that runs (calibration.csv was made with 0.6, before it was set from that file).
KAPPA = float(re.search(r'pub const KAPPA: f32 = ([0-9.]+);', open(sys.argv[5] + '/src/placement/estimate.rs').read())[1])
sys.path.insert(0, sys.argv[5] + '/experiments/results/refine-tuning/2026-11-28b')
import pfm
name, set_, n, rmse = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
w, h, img = pfm.read(f'ref-{name}.pfm')
mean = sum(sum(p) for r in img for p in r) / (w * h * 3)
d = json.load(open(f'r-{name}-{n}.json'))
est = d['stats']['error_estimates'][-1]['relative_rmse'] if 'stats' in d else d['cache']['error_estimates'][-1]['relative_rmse']
k1 = est / math.sqrt(KAPPA)
print(f'{name},{set_},{n},{rmse/mean:.4f},{k1:.4f},{est:.4f}')
PY
  done >> calibration.csv
done
