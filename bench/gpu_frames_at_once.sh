#!/usr/bin/env bash
# Frames rendered at once (FRAMES_AT_ONCE) by the pooled multi-kernel PT layouts at 0.92 M
# paths a frame (1280x720x1) against the same layouts' peak (1280x720x64, 59 M paths a frame),
# docs/performance.md "Frames at once". On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_frames_at_once.sh
# 1 s a point after the bench's warm-up; prints scene, FRAMES_AT_ONCE, layout, point,
# Mrays/s wall-clock and Mrays/s of GPU time.
set -uo pipefail
layouts=RegenerationPTmk1,RegenerationPTmk2,RegenerationPTmk3,StreamingPTmk1,StreamingPTmk2,StreamingPTmk3,WavefrontPT,NaivePTmk
for scene in cornell-mitsuba sponza; do
  for g in 1 4 16 64; do
    points=1280x720x1
    [ "$g" = 1 ] && points=1280x720x1,1280x720x64
    bash .gpu/run.sh lightgraph bench --scene $scene --graph pt --layouts $layouts --points $points --time 1s \
      --set FRAMES_AT_ONCE=$g --out /tmp/fo >/dev/null 2>&1 || { echo "$scene G=$g: failed"; continue; }
    tail -n +2 /tmp/fo/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps rest; do
      echo "$scene,G=$g,$layout,${w}x${h}x$spp,$(awk "BEGIN { printf \"%.0f,%.0f\", $rps / 1e6, $grps / 1e6 }")"
    done
  done
done
