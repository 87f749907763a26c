#!/usr/bin/env bash
# Frames rendered at once (FRAMES_AT_ONCE) by the pooled multi-kernel PT layouts at 0.92 M
# paths a frame (1280x720x1) against the same layouts' peak (1280x720x64, 59 M paths a frame),
# docs/performance.md "Frames at once". On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/pt/frames_at_once.sh
# 1 s a point after the bench's warm-up; prints `bench_rows` lines (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
layouts=RegenerationPTmk1,RegenerationPTmk2,RegenerationPTmk3,StreamingPTmk1,StreamingPTmk2,StreamingPTmk3,WavefrontPT,NaivePTmk
for scene in cornell-mitsuba sponza; do
  for g in 1 4 16 64; do
    points=1280x720x1
    [ "$g" = 1 ] && points=1280x720x1,1280x720x64
    bench_rows lightgraph "$scene N=$g" --scene $scene --graph pt --layouts $layouts --points $points --time 1s \
      --set FRAMES_AT_ONCE=$g
  done
done
