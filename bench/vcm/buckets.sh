#!/usr/bin/env bash
# VCMsk over the hash grid's buckets per light sub-path (PM_BUCKETS_PER_PATH) on Sponza at
# 1280x720 and on the diffuse Cornell box at 256x256 with 64 iterations a frame, against
# LVC-BPTsk (docs/performance.md, "Vertex connection and merging"). On the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/vcm/buckets.sh
# 2 s a point, two rounds; prints `bench_rows` lines (bench/common.sh) with the camera
# kernel's GPU ms.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
export KERNELS=camera
for r in 1 2; do
  bench_rows lightgraph "r$r sponza" --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
  for b in 1 2 4 8; do
    bench_rows lightgraph "r$r sponza buckets $b" --time 2s --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1 \
      --set PM_BUCKETS_PER_PATH=$b
    bench_rows lightgraph "r$r box buckets $b" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk \
      --points 256x256x64 --set PM_ITERATIONS=64 --set PM_BUCKETS_PER_PATH=$b
  done
done
