#!/usr/bin/env bash
# VCM iterations per second at 256x256 on the diffuse Cornell box with K iterations a frame
# (`--spp K --set PM_ITERATIONS=K`: one camera and one light sub-path per pixel an iteration,
# SmallVCM's setting), against LVC-BPTsk at the same frames (docs/performance.md, "Vertex
# connection and merging"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/vcm/iterations.sh
# 3 s a point after the bench's warm-up; prints `bench_rows` lines (bench/common.sh) with
# every kernel's GPU ms a frame; iterations/s are frames/s times K.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
for k in 1 2 4 8 16 32 64; do
  KERNELS=. bench_rows lightgraph "vcm K=$k" --scene cornell-diffuse --graph vcm --layouts VCMsk,VCMmk \
    --points 256x256x$k --time 3s --set PM_ITERATIONS=$k
  KERNELS=. bench_rows lightgraph "bpt-lvc K=$k" --scene cornell-diffuse --graph bpt-lvc --layouts LVC-BPTsk \
    --points 256x256x$k --time 3s
done
# The rate of large frames (one iteration of 1280x720).
bench_rows lightgraph "vcm 1280x720" --scene cornell-diffuse --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1 --time 3s
