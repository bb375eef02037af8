#!/usr/bin/env bash
# Each renderer's own noise on the Cornell box's emitter and the ceiling around it, at the 64 lowdiscrepancy
# pixel samples of the pbrt-v2 comparison (experiments/results/irc-peer/peer.md): `directlighting` over a crop window
# around the light (64×14 pixels), against pbrt-v3's own image of that window at 4096 samples. There the
# ceiling gets no direct light (the emitter faces down), so a pixel's error is the estimate of how much of it
# the emitter covers. Run from the repository root after `cargo build --release`; writes into $OUT
# (default /tmp/cachert-edge-noise) and prints the table (results.md).
set -euo pipefail
SCENES=../shared/scenes/bitterli-cornell-box-v3
V2=../shared/tools/pbrt-v2/pbrt
V3=../shared/tools/pbrt-v3/pbrt
OUT=${OUT:-/tmp/cachert-edge-noise}
for f in "$SCENES/direct-ref.pbrt" "$V2" "$V3"; do
  [ -e "$f" ] || { echo "skipped: $f is absent" >&2; exit 0; }
done
mkdir -p "$OUT"
# Columns 96–159 and rows 14–27 of the 256×256 film: the emitter and a border of ceiling around it.
CROP='"float cropwindow" [0.375 0.625 0.0546875 0.109375]'
v3scene() {
  sed -e "s/^Sampler.*/Sampler \"lowdiscrepancy\" \"integer pixelsamples\" [$1]/" \
      -e "s/^Film.*/Film \"image\" \"integer xresolution\" [256] \"integer yresolution\" [256] $CROP/" \
      "$SCENES/direct-ref.pbrt"
}
v3scene 4096 > "$OUT/truth.pbrt"
v3scene 64 > "$OUT/crop64.pbrt"
sed -e "s/^Film.*/Film \"image\" \"integer xresolution\" [256] \"integer yresolution\" [256] $CROP/" \
  "$SCENES/pbrt-v2/direct-v2.pbrt" > "$OUT/crop64-v2.pbrt"
"$V3" --quiet --nthreads 2 --outfile "$OUT/truth.pfm" "$OUT/truth.pbrt" > /dev/null
"$V3" --quiet --nthreads 2 --outfile "$OUT/v3.pfm" "$OUT/crop64.pbrt" > /dev/null
# cachert: 32 seeds. The same scene at 4096 samples, two seeds, for the truth's agreement.
for s in $(seq 0 31); do
  target/release/cachert render --quiet --nthreads 2 --seed "$s" --outfile "$OUT/cachert-$s.pfm" "$OUT/crop64.pbrt"
done
for s in 0 1; do
  target/release/cachert render --quiet --nthreads 2 --seed "$s" --outfile "$OUT/cachert-4096-$s.pfm" "$OUT/truth.pbrt"
done
# pbrt-v2 takes no seed; its render pass seeds each task by its number, and --ncores 1, 2, 4, …, 256 give
# 32, 64, …, 8192 tasks over this window (RoundUpPow2(max(32 · cores, pixels / 256))): 9 different streams.
for n in 1 2 4 8 16 32 64 128 256; do
  "$V2" --quiet --ncores "$n" --outfile "$OUT/v2-$n.pfm" "$OUT/crop64-v2.pbrt" > /dev/null 2>&1
done
# The table: each image's RMSE over the window against the truth (`cachert compare --window`; an image that is
# already the window's 64×14 is taken as it), written as its share of a 256×256 image's RMSE (× √(64·14 / 65536),
# so it compares with the "RMSE share of light + border" column of experiments/results/irc-peer/peer.md), and per
# renderer the runs' mean, sample sd, min and max.
share() {
  target/release/cachert compare --metric rmse --window 96,14,64,14 "$1" "$OUT/truth.pfm" |
    awk '$1 == "rmse" { printf "%.9f\n", $2 * sqrt(64 * 14 / 65536) }'
}
row() {
  local name=$1; shift
  for f in "$@"; do share "$f"; done | awk -v name="$name" '
    { v[NR] = $1; s += $1; if (NR == 1 || $1 < lo) lo = $1; if (NR == 1 || $1 > hi) hi = $1 }
    END { m = s / NR; for (i = 1; i <= NR; i++) q += (v[i] - m) ^ 2
          sd = NR > 1 ? sprintf("%.5f", sqrt(q / (NR - 1))) : "–"
          printf "| %s | %d | %.5f | %s | %.5f | %.5f |\n", name, NR, m, sd, lo, hi }'
}
echo "| renderer (lowdiscrepancy, 64 samples) | runs | mean | sd | min | max |"
echo "|---|---|---|---|---|---|"
row "cachert, seeds 0–31" $(for s in $(seq 0 31); do echo "$OUT/cachert-$s.pfm"; done)
row "pbrt-v2, --ncores 1–256" $(for n in 1 2 4 8 16 32 64 128 256; do echo "$OUT/v2-$n.pfm"; done)
row "pbrt-v3 (no seed)" "$OUT/v3.pfm"
row "cachert at 4096 samples, seeds 0–1 (the truth's own noise and any bias)" "$OUT/cachert-4096-0.pfm" "$OUT/cachert-4096-1.pfm"
