#!/usr/bin/env bash
# The full hash grid's tags (shaders/pm/cells.wgsl): the binary before them against the one
# after, VCMsk on Sponza at 1280x720 (against LVC-BPTsk) and on the diffuse Cornell box at
# 256x256 with 64 iterations a frame, with the default and other bucket counts, then PPMsk's
# camera-vertex queries on ModernHall (bench/gpu_pm_queries.sh) (docs/performance.md,
# "Photon mapping" and "Vertex connection and merging"). On the GPU machine from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza
# --scene ModernHall` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/gpu_grid_tags.sh
# 2 s a point, two interleaved rounds; prints `bench_rows` lines (bench/gpu_common.sh) with
# the camera kernel's GPU ms.
set -uo pipefail
source "$(dirname "$0")/gpu_common.sh"
export KERNELS=camera
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    bench_rows $bin "r$r $bin sponza" --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
    bench_rows $bin "r$r $bin sponza" --time 2s --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1
    bench_rows $bin "r$r $bin box" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk \
      --points 256x256x64 --set PM_ITERATIONS=64
  done
  for b in 1 8; do
    bench_rows lightgraph "r$r sponza buckets $b" --time 2s --scene sponza --graph vcm --layouts VCMsk \
      --points 1280x720x1 --set PM_BUCKETS_PER_PATH=$b
    bench_rows lightgraph "r$r box buckets $b" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk \
      --points 256x256x64 --set PM_ITERATIONS=64 --set PM_BUCKETS_PER_PATH=$b
  done
done
bash "$(dirname "$0")/gpu_pm_queries.sh"
