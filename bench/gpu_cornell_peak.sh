#!/usr/bin/env bash
# The single-kernel PT layouts on the Cornell box at 1280x720 over the paths a frame (16 to 64
# samples per pixel: 14.7 to 59 M paths), with frames at once (FRAMES_AT_ONCE) and workgroups of
# 64 (default) and 128 threads: issue 16's 1.6 Gsamples/s (docs/performance.md, "BVH build
# quality"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_cornell_peak.sh
# 2 s a point, two rounds; prints `bench_rows` lines (bench/gpu_common.sh).
set -uo pipefail
source "$(dirname "$0")/gpu_common.sh"
for r in 1 2; do
  for wg in 64 128; do
    bench_rows lightgraph "r$r wg $wg" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk \
      --points 1280x720x16,1280x720x32,1280x720x64 --time 2s --workgroup $wg
    bench_rows lightgraph "r$r wg $wg N=4" --scene cornell-mitsuba --graph pt --layouts NaivePTsk \
      --points 1280x720x16 --time 2s --workgroup $wg --set FRAMES_AT_ONCE=4
  done
done
