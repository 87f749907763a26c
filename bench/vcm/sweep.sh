#!/usr/bin/env bash
# Vertex connection and merging on the GPU machine (docs/performance.md, "Vertex connection
# and merging"), after a 10 s warm-up, REPEATS interleaved rounds of:
# - iterations per second on the diffuse Cornell box at 256x256 (one camera and one light
#   sub-path per pixel an iteration, SmallVCM's setting; its CPU rate is the issue's
#   reference), VCMsk and VCMmk, and LVC-BPTsk beside them;
# - samples per second on Sponza at 1280x720: VCMsk, VCMmk, LVC-BPTsk, LVC-BPTmk;
# - Table VII, time per iteration of VCMsk and VCMmk at 1280x720 on the glossy box with the
#   sun, LivingRoom, ModernHall and VeachBidir;
# then `explain`'s memory of VCM on Sponza (Table II). Run from the repo root with carry
# [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene LivingRoom --scene ModernHall --scene VeachBidir`.
#   bash bench/vcm/sweep.sh LOG [REPEATS] [SECONDS]
set -uo pipefail
log=${1:?usage: bash bench/vcm/sweep.sh LOG [REPEATS] [SECONDS]}
repeats=${2:-2}
secs=${3:-5}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
timed() {
  echo "== $*"
  lg render --time "${secs}s" --out "$out/x.exr" "$@" 2>&1 | grep -E "frames,|lvc_overflow|rror"
}
lg render --graph vcm --scene sponza --res 1280x720 --time 10s --out "$out/warm.exr" >/dev/null 2>&1
scenes=.gpu/scenes
for round in $(seq "$repeats"); do
  echo "#### round $round"
  for l in vcm:VCMsk vcm:VCMmk bpt-lvc:LVC-BPTsk; do
    timed --graph "${l%%:*}" --layout "${l##*:}" --scene cornell-diffuse --res 256x256
  done
  for l in vcm:VCMsk vcm:VCMmk bpt-lvc:LVC-BPTsk bpt-lvc:LVC-BPTmk; do
    timed --graph "${l%%:*}" --layout "${l##*:}" --scene sponza --res 1280x720
  done
  for s in cornell-glossy-sun $scenes/LivingRoom/living-room.gltf $scenes/ModernHall/staircase2.gltf \
    $scenes/VeachBidir/veach-bidir.gltf; do
    for l in VCMsk VCMmk; do timed --graph vcm --layout $l --scene "$s" --res 1280x720; done
  done
done
echo "#### memory"
lg explain --graph vcm --scene sponza --res 1280x720 2>/dev/null | grep -E "^layout|GPU memory|peak|lvc_|vcm_grid|grid_"
