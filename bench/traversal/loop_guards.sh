#!/usr/bin/env bash
# wgpu's loop guards and the PT pools (docs/performance.md, "Loop guards"). On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/traversal/loop_guards.sh sweep   # every layout on Sponza (and three PT layouts and VCMsk
#                                         # on the Cornell boxes) with --loop-guards on, then off
#   bash bench/traversal/loop_guards.sh pools   # the pooled PT layouts over their pools, 2 s a point
set -uo pipefail
source "$(dirname "$0")/../common.sh"
bin=${BIN:-lightgraph}
sweep() {
  bench_rows "$bin" warm --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1 >/dev/null
  for guards in on off; do
    bench_rows "$bin" "$guards sponza" --time 2s --scene sponza --graph pt --layouts all --points 1280x720x16 --loop-guards $guards
    for g in bpt-lvc vcm bpt-naive bpt-streaming lt ppm sppm pbpm; do
      bench_rows "$bin" "$guards sponza" --time 2s --scene sponza --graph $g --layouts all --points 1280x720x1 --loop-guards $guards
    done
    bench_rows "$bin" "$guards box" --time 2s --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk,StreamingPTmk1 \
      --points 1280x720x16 --loop-guards $guards
    bench_rows "$bin" "$guards box" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 \
      --set PM_ITERATIONS=64 --loop-guards $guards
  done
}
pools() {
  local p="--time 2s --scene sponza --graph pt --points 1280x720x16"
  bench_rows "$bin" warm $p --layouts StreamingPTmk2 >/dev/null
  for t in 1048576 2097152 4194304; do
    for n in 1 4; do
      bench_rows "$bin" "threads $t, $n at once" $p --layouts StreamingPTmk1,StreamingPTmk2,StreamingPTmk3,WavefrontPT,RegenerationPTmk2 \
        --set FRAMES_AT_ONCE=$n --threads $t
    done
  done
}
"${1:-sweep}"
