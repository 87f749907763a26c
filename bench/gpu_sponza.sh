#!/usr/bin/env bash
# Crytek Sponza measurements of docs/performance.md, run on the GPU machine from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
# every named PT layout at 1280x720 over 1 to 64 samples per pixel per frame, with the CWBVH
# and the BVH2; --layout auto at 4 samples per pixel per frame; a 20 s preview render.
#   bash bench/gpu_sponza.sh OUT_DIR [SECONDS_PER_POINT]
set -uo pipefail
out=${1:?usage: bash bench/gpu_sponza.sh OUT_DIR [SECONDS]}
secs=${2:-1}
points=1280x720x1,1280x720x4,1280x720x16,1280x720x64
mkdir -p "$out"
for bvh in cwbvh bvh2; do
  bash .gpu/run.sh lightgraph bench --scene sponza --graph pt --layouts all --bvh $bvh --points $points --time ${secs}s --out "$out/$bvh" 2>&1 | grep -v "^|"
done
rm -f "$out"/*/bench.csv
bash .gpu/run.sh lightgraph render --scene sponza --layout auto --tune-time 300ms --res 1280x720 --spp 4 --time 20s --out "$out/auto/sponza.exr" 2>&1 | grep -v "^  "
rm -f "$out/auto/sponza.exr"
