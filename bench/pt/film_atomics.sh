#!/usr/bin/env bash
# What the film's atomic adds cost PT's one-kernel layouts on the Cornell box (issue 16's
# 1.6 Gsamples/s), and the pixel order: NaivePTsk and RegenerationPTsk at 1280x720x16 and x64,
# workgroups of 64 and 128, with the bundle's binary (`lightgraph`), with a build whose film
# adds no light (`lightgraph-noatomic`: the adds guarded by a test no sample passes, so the
# samples are still computed; a bound, not a renderer), and with TILED_PIXELS=false. On the
# GPU machine from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh`
# and the second binary in .gpu/bin:
#   bash bench/pt/film_atomics.sh
# ROUNDS interleaved rounds (default 2), 2 s a point.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
for r in $(seq "${ROUNDS:-2}"); do
  for wg in 64 128; do
    for bin in lightgraph lightgraph-noatomic; do
      bench_rows $bin "r$r $bin wg $wg" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk \
        --points 1280x720x16,1280x720x64 --time 2s --workgroup "$wg"
    done
    bench_rows lightgraph "r$r untiled wg $wg" --scene cornell-mitsuba --graph pt --layouts NaivePTsk,RegenerationPTsk \
      --points 1280x720x16,1280x720x64 --time 2s --workgroup "$wg" --set TILED_PIXELS=false
  done
done
