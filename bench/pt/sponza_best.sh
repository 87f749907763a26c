#!/usr/bin/env bash
# Issue 16's Sponza figure (PT at 1280x720x16, 14.75 M paths a frame): the four fastest PT
# layouts one frame at a time and 4 frames at once, and RegenerationPTsk with 256 threads a
# workgroup (docs/performance.md, "The shadow ray emitted last"), ROUNDS interleaved rounds
# (default 2), 2 s a point. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/pt/sponza_best.sh
set -uo pipefail
source "$(dirname "$0")/../common.sh"
for r in $(seq "${ROUNDS:-2}"); do
  for n in 1 4; do
    bench_rows lightgraph "r$r at once $n" --scene sponza --graph pt --time 2s --points 1280x720x16 \
      --layouts NaivePTsk,RegenerationPTsk,StreamingPTmk1,StreamingPTmk2 --set FRAMES_AT_ONCE=$n
  done
  bench_rows lightgraph "r$r wg 256" --scene sponza --graph pt --time 2s --points 1280x720x16 \
    --layouts RegenerationPTsk --workgroup 256
done
