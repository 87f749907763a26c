#!/usr/bin/env bash
# The layout sweep of docs/performance.md, run on the GPU machine from the repo root with
# carry [".gpu"]: every named PT layout on Mitsuba's Cornell box over the paper's range of
# paths per frame, with the compressed wide BVH and with the BVH2; then --layout auto at
# 1280x720, 4 samples per pixel per frame.
#   bash bench/gpu_layouts.sh OUT_DIR [SECONDS_PER_POINT]
set -uo pipefail
out=${1:?usage: bash bench/gpu_layouts.sh OUT_DIR [SECONDS]}
secs=${2:-1}
scene=${SCENE:-cornell-mitsuba}
mkdir -p "$out"
for bvh in cwbvh bvh2; do
  bash .gpu/run.sh lightgraph bench --scene "$scene" --graph pt --layouts all --bvh $bvh --time ${secs}s --out "$out/$bvh" 2>&1 | tee /tmp/$bvh.log | grep -v "^|"
done
bash .gpu/run.sh lightgraph render --scene "$scene" --layout auto --tune-time 300ms --res 1280x720 --spp 4 --time 5s --out "$out/auto/render.exr" 2>&1 | tee "$out/auto.log" | grep -v "^  "
rm -f "$out/auto/render.exr" "$out/auto/render.png"
