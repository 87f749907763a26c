#!/usr/bin/env bash
# The PT layout sweeps of docs/performance.md ("Path-tracing layouts on the H200" on Mitsuba's
# Cornell box, "Crytek Sponza" with SCENE=sponza), run on the GPU machine from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh` (`--scene CrytekSponza` for Sponza):
# every named PT layout with the compressed wide BVH and with the BVH2, then --layout auto at
# 1280x720, 4 samples per pixel per frame (its PNG stays in OUT_DIR/auto).
#   bash bench/pt/layouts.sh OUT_DIR [SECONDS_PER_POINT]
#   SCENE=sponza bash bench/pt/layouts.sh OUT_DIR [SECONDS_PER_POINT]
# SCENE (default cornell-mitsuba); POINTS, the bench's --points (default: bench's own range of
# paths per frame, the paper's; with SCENE=sponza 1280x720 at 1, 4, 16 and 64 samples per pixel
# per frame); AUTO_SECONDS, the --layout auto render's time (default 5; 20 with SCENE=sponza,
# the preview of docs/perf/sponza-h200-20s.png).
set -uo pipefail
out=${1:?usage: [SCENE=S] bash bench/pt/layouts.sh OUT_DIR [SECONDS]}
secs=${2:-1}
scene=${SCENE:-cornell-mitsuba}
if [ "$scene" = sponza ]; then
  points=${POINTS-1280x720x1,1280x720x4,1280x720x16,1280x720x64}
  auto_secs=${AUTO_SECONDS:-20}
else
  points=${POINTS-}
  auto_secs=${AUTO_SECONDS:-5}
fi
mkdir -p "$out"
for bvh in cwbvh bvh2; do
  bash .gpu/run.sh lightgraph bench --scene "$scene" --graph pt --layouts all --bvh $bvh ${points:+--points "$points"} \
    --time "${secs}s" --out "$out/$bvh" 2>&1 | tee "$out/$bvh.log" | grep -v "^|"
done
bash .gpu/run.sh lightgraph render --scene "$scene" --layout auto --tune-time 300ms --res 1280x720 --spp 4 \
  --time "${auto_secs}s" --out "$out/auto/$scene.exr" 2>&1 | tee "$out/auto.log" | grep -v "^  "
rm -f "$out/auto/$scene.exr"
