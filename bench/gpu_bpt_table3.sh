#!/usr/bin/env bash
# Table III again with StreamingBPT rendering 16 frames at once (docs/performance.md,
# "Bidirectional path tracing"): a 40 s LVC-BPT reference, then `lightgraph compare` with
# StreamingBPT@FRAMES_AT_ONCE=16 as the baseline, StreamingBPT one frame at a time, NaiveBPT,
# LVC-BPTsk and LVC-BPTmk, 8 s each, on the glossy Cornell box with a point light and on
# Crytek Sponza. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_bpt_table3.sh
set -uo pipefail
lg() { bash .gpu/run.sh lightgraph "$@"; }
work=$(mktemp -d)
for scene in cornell-glossy-point:512x512:4 sponza:1280x720:1; do
  IFS=: read -r name res spp <<<"$scene"
  lg reference --graph bpt-lvc --layout LVC-BPTmk --scene "$name" --res "$res" --spp "$spp" --time 40s \
    --out "$work/$name/ref.exr" 2>&1 | tail -1
  lg compare --scene "$name" --res "$res" --spp "$spp" --reference "$work/$name/ref.exr" --time 8s \
    --baseline bpt-streaming:StreamingBPT@FRAMES_AT_ONCE=16 \
    --runs bpt-streaming:StreamingBPT@FRAMES_AT_ONCE=16,bpt-streaming:StreamingBPT,bpt-naive:NaiveBPT,bpt-lvc:LVC-BPTsk,bpt-lvc:LVC-BPTmk \
    --out "$work/$name/compare" 2>&1 | grep -E "^\|"
done
