#!/usr/bin/env bash
# VCM iterations per second at 256x256 on the diffuse Cornell box with K iterations a frame
# (`--spp K --set PM_ITERATIONS=K`: one camera and one light sub-path per pixel an iteration,
# SmallVCM's setting), against LVC-BPTsk at the same frames (docs/performance.md, "Vertex
# connection and merging"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_vcm_iterations.sh
# 3 s a point after the bench's warm-up; prints graph, layout, K, frames/s, iterations/s and
# the GPU milliseconds per frame of each kernel (the bench's CSV columns 6, 7, 12 and 14).
set -uo pipefail
run() { # graph layouts K
  bash .gpu/run.sh lightgraph bench --scene cornell-diffuse --graph "$1" --layouts "$2" \
    --points 256x256x"$3" --time 3s ${4:+--set PM_ITERATIONS=$3} --out /tmp/vi >/dev/null 2>&1 \
    || { echo "$1 $2 K=$3: failed"; return; }
  tail -n +2 /tmp/vi/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps fps mem kms; do
    echo "$1,$layout,K=$3,$fps frames/s,$(awk "BEGIN { printf \"%.0f\", $fps * $3 }") iterations/s,kernels: $kms"
  done
}
for k in 1 2 4 8 16 32 64; do
  run vcm VCMsk,VCMmk "$k" merge
  run bpt-lvc LVC-BPTsk "$k"
done
# The rate of large frames (one iteration of 1280x720).
bash .gpu/run.sh lightgraph bench --scene cornell-diffuse --graph vcm --layouts VCMsk,VCMmk \
  --points 1280x720x1 --time 3s --out /tmp/vl >/dev/null 2>&1
cut -d, -f1,6,7,11,12 /tmp/vl/bench.csv
