#!/usr/bin/env bash
# PT's single-kernel layouts on the Cornell box (cornell-mitsuba, 1280x720x16) over the BVH and
# the workgroup size, and the BVH build's A/B against the binary before it (docs/performance.md,
# "BVH build quality"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza` and the binary before the
# BVH change copied to .gpu/bin/lightgraph-old:
#   bash bench/traversal/bvh_build.sh
# 2 s a point; prints `bench_rows` lines (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    bench_rows $bin "r$r $bin" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk --points 1280x720x16 --time 2s
    bench_rows $bin "r$r $bin" --scene sponza --graph pt --layouts NaivePTsk,StreamingPTmk1,StreamingPTmk2,RegenerationPTsk \
      --points 1280x720x16 --time 2s
  done
done
for bvh in bvh2 cwbvh; do
  for wg in 32 64 128 256; do
    bench_rows lightgraph "$bvh workgroup=$wg" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk \
      --points 1280x720x16 --time 2s --bvh $bvh --workgroup $wg
  done
done
