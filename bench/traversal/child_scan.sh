#!/usr/bin/env bash
# The CWBVH's child loop: a loop of eight slots the driver unrolls, or a bit scan over the
# occupied slots (the constant CWBVH_CHILD_SCAN), with and without wgpu's loop guards
# (docs/performance.md, "The CWBVH's child loop"). On the GPU machine from the repo root with
# carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/traversal/child_scan.sh fused   # PT, LVC-BPT, VCM, NaiveBPT on Sponza, the box rows
#   bash bench/traversal/child_scan.sh rest    # StreamingBPT, LT and the photon-mapping graphs on Sponza
#   BEFORE=lightgraph-old bash bench/traversal/child_scan.sh ab   # the layouts it changed, the binary
#                                         # BEFORE (copied into .gpu/bin) against today's, 2 rounds
# fused and rest run each layout three ways: as shipped, then the scan with the guards on, then off.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
bin=${BIN:-lightgraph}
# combos ARGS...: one bench run per way.
combos() {
  bench_rows "$bin" "shipped" "$@"
  bench_rows "$bin" "scan, guards on" "$@" --set CWBVH_CHILD_SCAN=true --loop-guards on
  bench_rows "$bin" "scan, guards off" "$@" --set CWBVH_CHILD_SCAN=true --loop-guards off
}
fused() {
  bench_rows "$bin" warm --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1 >/dev/null
  combos --time 2s --scene sponza --graph pt --layouts all --points 1280x720x16
  for g in bpt-lvc vcm bpt-naive; do
    combos --time 2s --scene sponza --graph $g --layouts all --points 1280x720x1
  done
  combos --time 2s --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk,RegenerationPTmk1 --points 1280x720x16
  combos --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 --set PM_ITERATIONS=64
}
rest() {
  bench_rows "$bin" warm --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1 >/dev/null
  for g in bpt-streaming lt ppm sppm pbpm; do
    combos --time 2s --scene sponza --graph $g --layouts all --points 1280x720x1
  done
}
ab() {
  for round in 1 2; do
    for b in "${BEFORE:?BEFORE names the binary before}" "$bin"; do
      KERNELS=camera bench_rows "$b" "r$round $b sponza" --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk,LVC-BPTmk --points 1280x720x1
      KERNELS=camera bench_rows "$b" "r$round $b sponza" --time 2s --scene sponza --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1
      bench_rows "$b" "r$round $b sponza" --time 2s --scene sponza --graph bpt-naive --layouts NaiveBPTmk --points 1280x720x1
      bench_rows "$b" "r$round $b sponza" --time 2s --scene sponza --graph pt --layouts NaivePTsk,StreamingPTmk2 --points 1280x720x16
      bench_rows "$b" "r$round $b box" --time 2s --scene cornell-mitsuba --graph pt --layouts NaivePTsk --points 1280x720x16
      KERNELS=camera bench_rows "$b" "r$round $b box" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 \
        --set PM_ITERATIONS=64
    done
  done
}
"${1:-fused}"
