#!/usr/bin/env bash
# Fast by default (issue 43, item 5; docs/performance.md, "Default layouts against the
# fastest"): each graph's default layout (PT, LVC-BPT, PPM, VCM) against its fastest named
# layout on Sponza, the Cornell boxes and the study scenes at their default sizes, one sample a
# pixel a frame, SECS (default 1) seconds a layout after a warm-up frame; then `render --layout
# auto` on Sponza timed from a fresh layout cache and again from the cache. Run from the repo
# root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza --scene ModernHall --scene VeachBidir`
# (and a second call with LivingRoom for SCENES=living-room:1280x720):
#   bash bench/defaults.sh LOG
set -uo pipefail
log=${1:?usage: bash bench/defaults.sh LOG}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/common.sh"
secs=${SECS:-1}
# SCENES: scene:WxH entries (the bundle's 64 MiB do not hold all four shared scenes at once).
scenes=${SCENES:-"sponza:1280x720 cornell-diffuse:512x512 cornell-mitsuba:256x256 cornell-glossy-point:512x512
  cornell-glossy-sun:512x512 living-room:1280x720 modern-hall:1280x720 veach-bidir:720x720"}
lg render --graph pt --scene sponza --res 1280x720 --frames 200 --out "$out/warm.exr" >/dev/null 2>&1
for entry in $scenes; do
  scene=${entry%%:*}
  for graph in pt bpt-lvc ppm vcm; do
    echo "== $scene $graph default $(grep -o 'default_layout: "[^"]*"' "graphs/$graph.ron")"
    bench_rows lightgraph "$scene $graph" --time "${secs}s" --scene "$scene" --graph "$graph" \
      --layouts all --points "${entry##*:}x1"
  done
done
export LIGHTGRAPH_CACHE="$out/cache"
for round in fresh cached; do
  start=$(date +%s.%N)
  lg render --scene sponza --graph pt --layout auto --frames 1 --out "$out/auto-$round.exr" --force 2>&1 |
    grep -E "winner|from the layout cache|rror"
  echo "== --layout auto on sponza, $round: $(awk "BEGIN { printf \"%.1f\", $(date +%s.%N) - $start }") s"
done
