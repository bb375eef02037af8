#!/usr/bin/env bash
# Regenerates the pbrt-v3 `path` / `directlighting` references in this folder (see README.md).
#
#   tests/data/pbrt-v3/shading/make.sh            # every reference
#   tests/data/pbrt-v3/shading/make.sh NAME...    # only these (names as in the table below)
#   tests/data/pbrt-v3/shading/make.sh --header NAME   # print the render options of NAME, render nothing
#   tests/data/pbrt-v3/shading/make.sh --list     # print the variant table, expanded, one per line
#   tests/data/pbrt-v3/shading/make.sh --warnings [NAME...]  # 1 spp into a temporary folder, without
#                                      --quiet, printing what pbrt-v3 writes on stderr (its warnings)
#
# Each reference is a shared scene (../shared/scenes, never copied into the repository) with only its render
# options replaced: the scene's Integrator, Sampler and Film directives before WorldBegin are dropped and the
# lines below are put in front; Camera, LookAt/Transform, PixelFilter and the world are unchanged. The result
# is piped to pbrt-v3 on stdin with the scene's folder as the working directory, so relative Include, mesh
# and texture paths resolve as they do for the file itself. Only this script needs pbrt-v3; tests read the
# PFMs. Each run appends "name user-CPU-seconds" (/usr/bin/time -f %U) to times.log here.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../../.." && pwd)
SCENES=${SCENES:-$ROOT/../shared/scenes}
PBRT=${PBRT:-$ROOT/../shared/tools/pbrt-v3/pbrt}
case $PBRT in /*) ;; *) PBRT=$PWD/$PBRT ;; esac # the renders run in the scene folders
OUT=${OUT:-$HERE}
H=hackmad-pbrt-v3-rs-tests
DL='Integrator "directlighting" "string strategy" ["all"] "integer maxdepth" [5]'
# Substitutions for files the hackmad scenes name outside their repository (absent here; see README.md):
# the environment maps become the Cornell box's path-ref.pfm, the dragon PLY a sphere of radius 60 on the
# rotation axis, the gold SPD files gold's RGB eta/k, lines.png the repository's own checkerboard.png.
ENVMAP='"../../bitterli-cornell-box-v3/path-ref.pfm"'
RENO="s#\"../../../pbrt-v3-scenes/sanmiguel/textures/RenoSuburb01_sm.exr\"#$ENVMAP#"
WELLS="s#\"../../../pbrt-v3-scenes/dragon/textures/20060807_wells6_hd.exr\"#$ENVMAP#"
DRAGON='s#Shape "plymesh" "string filename" "../../../pbrt-v3-scenes/dragon/geometry/dragon_remeshed.ply"#Translate 0 60 0 Shape "sphere" "float radius" [60]#'
GOLD='s#"spectrum eta" "../../../pbrt-v3-scenes/dragon/spds/Au.eta.spd"#"rgb eta" [0.143 0.374 1.442]#;s#"spectrum k" "../../../pbrt-v3-scenes/dragon/spds/Au.k.spd"#"rgb k" [3.983 2.385 1.603]#'
LINES='s#"../../../pbrt-v3-scenes/simple/textures/lines.png"#"../images/checkerboard.png"#'

# name | scene folder | scene file | Integrator line | spp | width | height [| substitutions]
# The substitutions are a sed script applied to the whole scene (used only where a file the scene names
# does not exist; the README says which).
VARIANTS=(
  # 1. path, maxdepth 5, default rrthreshold (1) and lightsamplestrategy (spatial)
  'path-veach-mis|pbrtv3scenes-veach-mis|mis.pbrt|Integrator "path" "integer maxdepth" [5]|7500|128|96'
  'path-staircase2|bitterli-staircase2|scene-v3.pbrt|Integrator "path" "integer maxdepth" [5]|2500|128|128'
  'path-bathroom|bitterli-bathroom|scene-v3.pbrt|Integrator "path" "integer maxdepth" [5]|1200|128|128'
  'path-buddha-fractal|pbrtv3scenes-buddha-fractal|buddha-fractal.pbrt|Integrator "path" "integer maxdepth" [5]|3000|80|128'
  # 3. the non-default light selection strategies on the Cornell box
  'direct-one-cornell|bitterli-cornell-box-v3|scene.pbrt|Integrator "directlighting" "string strategy" ["one"] "integer maxdepth" [5]|10000|128|128'
  'path-uniform-cornell|bitterli-cornell-box-v3|scene.pbrt|Integrator "path" "integer maxdepth" [5] "string lightsamplestrategy" ["uniform"]|1400|128|128'
  # 2. directlighting (strategy all, maxdepth 5) on hackmad feature scenes, whose "whitted" is replaced
  "direct-point|$H/lights|point.pbrt|$DL|4096|96|96"
  "direct-spot|$H/lights|spot.pbrt|$DL|4096|96|96"
  "direct-distant|$H/lights|distant.pbrt|$DL|4096|96|96"
  "direct-diffuse|$H/lights|diffuse.pbrt|$DL|1024|96|96"
  "direct-infinite-no-map|$H/lights|infinite-no-map.pbrt|$DL|8192|96|96"
  "direct-infinite-with-map|$H/lights|infinite-with-map.pbrt|$DL|4096|96|96|$RENO"
  "direct-plastic|$H/materials|plastic.pbrt|$DL|4096|80|80|$DRAGON;$WELLS"
  "direct-metal|$H/materials|metal.pbrt|$DL|4096|80|80|$DRAGON;$WELLS;$GOLD"
  "direct-glass|$H/materials|glass.pbrt|$DL|3072|80|80|$DRAGON;$WELLS"
  "direct-substrate|$H/materials|substrate.pbrt|$DL|4096|80|80|$DRAGON;$WELLS"
  "direct-uber|$H/materials|uber.pbrt|$DL|4096|80|80|$DRAGON;$WELLS"
  "direct-mix|$H/materials|mix.pbrt|$DL|2048|80|80|$DRAGON;$WELLS"
  "direct-translucent|$H/materials|translucent.pbrt|$DL|4096|80|80|$DRAGON;$WELLS"
  "direct-mirror|$H/materials|mirror.pbrt|$DL|2048|80|80|$DRAGON;$WELLS"
  "direct-2d-checkerboard|$H/textures|2d-checkerboard.pbrt|$DL|1536|96|96"
  "direct-2d-mappings|$H/textures|2d-mappings.pbrt|$DL|1536|128|64"
  "direct-trilinear-filtering|$H/textures|trilinear-filtering.pbrt|$DL|1536|96|96|$LINES"
  "direct-scale|$H/textures|scale.pbrt|$DL|1536|96|96"
  "direct-mix-texture|$H/textures|mix.pbrt|$DL|1536|96|96"
)

# Strips the Integrator, Sampler and Film directives (with their continuation lines) before WorldBegin.
strip_options() {
  awk '
    !world && /^[ \t]*WorldBegin/ { world = 1 }
    world { print; next }
    {
      if (match($0, /^[ \t]*[A-Za-z_]+/)) {
        word = substr($0, RSTART, RLENGTH); gsub(/[ \t]/, "", word)
        skip = (word == "Integrator" || word == "Sampler" || word == "Film")
      }
      if (!skip) print
    }'
}

# Prints the replaced render options of one variant.
header() {
  local name=$1 integrator=$2 spp=$3 w=$4 h=$5
  printf '%s\n' "$integrator" \
    "Sampler \"random\" \"integer pixelsamples\" [$spp]" \
    "Film \"image\" \"integer xresolution\" [$w] \"integer yresolution\" [$h]"
}

run_variant() {
  local name dir file integrator spp w h extra
  IFS='|' read -r name dir file integrator spp w h extra <<<"$1"
  spp=${SPP:-$spp} # SPP=n overrides every variant (for timing trials, with OUT=elsewhere)
  if [ "$MODE" = list ]; then printf '%s\n' "$1"; return; fi
  if [ "$MODE" = header ]; then header "$name" "$integrator" "$spp" "$w" "$h"; return; fi
  if [ "$MODE" = warnings ]; then
    echo "== $name" >&2
    ( cd "$SCENES/$dir" &&
      { header "$name" "$integrator" 1 "$w" "$h"; strip_options < "$file" | sed -e "${extra:-}"; } |
      "$PBRT" --nthreads 1 --logdir "${TMPDIR:-/tmp}" --outfile "$WTMP/$name.pfm" >/dev/null )
    return
  fi
  echo "== $name ($dir/$file, $spp spp, ${w}x$h)" >&2
  local log; log=$(mktemp)
  ( cd "$SCENES/$dir" &&
    { echo "# variant of $dir/$file: render options replaced"; header "$name" "$integrator" "$spp" "$w" "$h";
      strip_options < "$file" | sed -e "${extra:-}"; } |
    /usr/bin/time -f %U -o "$log" "$PBRT" --quiet --nthreads 1 --logdir "${TMPDIR:-/tmp}" \
      --outfile "$OUT/$name.pfm" )
  echo "$name $(tail -n 1 "$log")" | tee -a "$OUT/times.log" >&2
  rm -f "$log"
}

MODE=render
case ${1:-} in --header) MODE=header; shift ;; --warnings) MODE=warnings; shift ;; --list) MODE=list; shift ;; esac
WTMP=$(mktemp -d)
trap 'rm -rf "$WTMP"' EXIT
for v in "${VARIANTS[@]}"; do
  case $v in \#*) continue ;; esac
  name=${v%%|*}
  if [ $# -eq 0 ]; then run_variant "$v"; continue; fi
  for want in "$@"; do [ "$want" = "$name" ] && run_variant "$v"; done
done
