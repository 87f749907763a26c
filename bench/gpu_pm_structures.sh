#!/usr/bin/env bash
# The paper's Table VI in short (docs/performance.md, "Photon mapping"): PPM with each structure
# for the same wall-clock time against a path-traced reference of the glossy Cornell box with a
# point light (PT reaches every path there), the RMSE each reaches. Run from the repo root on
# the GPU machine with carry [".gpu"] after ../shared/tools/gpu-bundle.sh.
#   bash bench/gpu_pm_structures.sh LOG [SECONDS]
set -uo pipefail
log=${1:?usage: bash bench/gpu_pm_structures.sh LOG [SECONDS]}
secs=${2:-15}
exec > >(tee "$log") 2>&1
lg() { bash .gpu/run.sh lightgraph "$@"; }
out=$(mktemp -d)
lg reference --graph pt --layout StreamingPTmk2 --scene cornell-glossy-point --res 512x512 --spp 4 \
  --time "$((secs * 4))s" --out "$out/ref.exr" 2>&1 | tail -2
for st in 0 1 3; do
  echo "== PM_STRUCTURE=$st"
  lg render --graph ppm --scene cornell-glossy-point --res 512x512 --spp 4 --time "${secs}s" --set PM_STRUCTURE=$st \
    --set PM_WHILE_QUERY=false --reference "$out/ref.exr" --out "$out/x.exr" 2>&1 | grep -E "frames,|rmse|RMSE|rror" | tail -3
done
