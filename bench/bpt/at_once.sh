#!/usr/bin/env bash
# Frames rendered at once (FRAMES_AT_ONCE) by StreamingBPT and NaiveBPT on the Cornell boxes at
# 512x512x4 (issue 16's StreamingBPT target), and by PT's best layouts at 1280x720x16
# (docs/performance.md, "Frames at once"). On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/bpt/at_once.sh
# Prints `bench_rows` lines (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
point() { # scene graph layouts points N [threads]
  bench_rows lightgraph "$1 N=$5 threads=${6:-layout}" --scene "$1" --graph "$2" --layouts "$3" --points "$4" --time 3s \
    --set FRAMES_AT_ONCE="$5" ${6:+--threads $6}
}
for scene in cornell-glossy-point cornell-diffuse; do
  for n in 1 4 16; do
    point $scene bpt-streaming StreamingBPT 512x512x4 $n
    point $scene bpt-naive NaiveBPT,NaiveBPTmk 512x512x4 $n
  done
  point $scene bpt-streaming StreamingBPT 512x512x4 16 1048576
done
for n in 1 4; do
  point sponza pt StreamingPTmk1,StreamingPTmk2 1280x720x16 $n
  point cornell-mitsuba pt NaivePTsk,RegenerationPTsk,StreamingPTmk1 1280x720x16 $n
done
