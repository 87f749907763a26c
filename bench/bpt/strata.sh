#!/usr/bin/env bash
# NaiveBPT's and StreamingBPT's light sub-paths stratified among the frame's samples
# (docs/performance.md, "Light sub-paths started close together"), LIGHT_STRATA false against
# true (the default), ROUNDS interleaved rounds (default 2). Part `sponza`: `bench` rows of
# NaiveBPT, NaiveBPTmk and StreamingBPT on Sponza (the sun) and cornell-mitsuba (an area light)
# at 1280x720x1, 2 s a point. Part `at-once`: StreamingBPT's best setting on the Cornell boxes
# (issue 16's 3x; bench/bpt/at_once.sh): 512x512x4, 16 frames at once, a pool of 2^20
# samples, 3 s a point. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/bpt/strata.sh [sponza|at-once|all]
set -uo pipefail
source "$(dirname "$0")/../common.sh"
sponza_part() {
  for r in $(seq "${ROUNDS:-2}"); do
    for strata in false true; do
      for scene in sponza cornell-mitsuba; do
        bench_rows lightgraph "r$r strata $strata $scene" --time 2s --scene $scene --graph bpt-naive \
          --layouts NaiveBPT,NaiveBPTmk --points 1280x720x1 --set LIGHT_STRATA=$strata
        bench_rows lightgraph "r$r strata $strata $scene" --time 2s --scene $scene --graph bpt-streaming \
          --layouts StreamingBPT --points 1280x720x1 --set LIGHT_STRATA=$strata
      done
    done
  done
}
at_once_part() {
  for r in $(seq "${ROUNDS:-2}"); do
    for strata in false true; do
      for scene in cornell-glossy-point cornell-diffuse; do
        bench_rows lightgraph "r$r strata $strata $scene" --time 3s --scene $scene --graph bpt-streaming \
          --layouts StreamingBPT --points 512x512x4 --set FRAMES_AT_ONCE=16 --threads 1048576 --set LIGHT_STRATA=$strata
      done
    done
  done
}
case ${1:-all} in
  sponza) sponza_part ;;
  at-once) at_once_part ;;
  all) sponza_part; at_once_part ;;
  *) echo "usage: bash bench/bpt/strata.sh [sponza|at-once|all]" >&2; exit 2 ;;
esac
