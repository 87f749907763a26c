#!/usr/bin/env bash
# VCMsk and LVC-BPTsk on Sponza at 1280x720 over their pool of persistent threads and their
# workgroup size (docs/performance.md, "Vertex connection and merging"). On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene
# CrytekSponza`:
#   bash bench/vcm/occupancy.sh
# 2 s a point; prints `bench_rows` lines (bench/common.sh) with the camera kernel's GPU ms.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
export KERNELS=camera
for g in "vcm VCMsk" "bpt-lvc LVC-BPTsk"; do
  set -- $g
  bench_rows lightgraph "$1 default" --scene sponza --graph $1 --layouts $2 --points 1280x720x1 --time 2s
  for t in 131072 262144 524288; do
    bench_rows lightgraph "$1 threads=$t" --scene sponza --graph $1 --layouts $2 --points 1280x720x1 --time 2s --threads $t
  done
  for w in 32 64 128 256; do
    bench_rows lightgraph "$1 workgroup=$w" --scene sponza --graph $1 --layouts $2 --points 1280x720x1 --time 2s --workgroup $w
  done
done
