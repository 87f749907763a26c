#!/usr/bin/env bash
# PT's one-kernel layouts over the workgroup size (docs/performance.md, "BVH build quality":
# "Workgroups of the one-kernel layouts" and "The Cornell box's peak"): NaivePTsk and
# RegenerationPTsk with workgroups of WORKGROUPS (default 64 128 256) on the Cornell box at the
# points POINTS (default 1280x720x16,1280x720x64: 14.7 M and 59 M paths a frame) and on Sponza
# at 1280x720x16 (SPONZA=0 leaves Sponza out); with AT_ONCE=N also NaivePTsk on the Cornell box
# at 1280x720x16 rendering N frames at once. ROUNDS interleaved rounds (default 2), 2 s a
# point. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/pt/workgroups.sh
#   WORKGROUPS="64 128" POINTS=1280x720x16,1280x720x32,1280x720x64 AT_ONCE=4 SPONZA=0 bash bench/pt/workgroups.sh
# (the second: "The Cornell box's peak"). Prints `bench_rows` lines (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
for r in $(seq "${ROUNDS:-2}"); do
  for wg in ${WORKGROUPS:-64 128 256}; do
    bench_rows lightgraph "r$r wg $wg cornell" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk \
      --points "${POINTS:-1280x720x16,1280x720x64}" --time 2s --workgroup "$wg"
    [ -z "${AT_ONCE:-}" ] || bench_rows lightgraph "r$r wg $wg cornell N=$AT_ONCE" --scene cornell-mitsuba --graph pt \
      --layouts NaivePTsk --points 1280x720x16 --time 2s --workgroup "$wg" --set FRAMES_AT_ONCE="$AT_ONCE"
    [ "${SPONZA:-1}" = 0 ] || bench_rows lightgraph "r$r wg $wg sponza" --scene sponza --graph pt \
      --layouts NaivePTsk,RegenerationPTsk --points 1280x720x16 --time 2s --workgroup "$wg"
  done
done
