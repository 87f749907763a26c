#!/usr/bin/env bash
# PT's `material` taking the surface and BSDF that `logic` set up when the two run fused
# (shaders/common/path.wgsl, `PathVertex`): the binary before against the one after, PT
# layouts (LAYOUTS, default five) on the Cornell box and on Sponza at 1280x720x16 (14.7 M
# paths a frame), and NaivePTsk with a workgroup of 128 at 1280x720x64 (docs/performance.md,
# "A bounce's vertex set up once"; also for "The shadow ray emitted last").
# On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza` and the binary before copied to
# .gpu/bin/lightgraph-old:
#   bash bench/pt/path_vertex.sh
# 2 s a point, ROUNDS interleaved rounds (default 2); prints `bench_rows` lines
# (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
layouts=${LAYOUTS:-NaivePTsk,RegenerationPTsk,StreamingPTmk1,StreamingPTmk2,WavefrontPT}
for r in $(seq "${ROUNDS:-2}"); do
  for bin in lightgraph-old lightgraph; do
    bench_rows $bin "r$r $bin" --scene cornell-mitsuba --graph pt --layouts $layouts --points 1280x720x16 --time 2s
    bench_rows $bin "r$r $bin wg 128" --scene cornell-mitsuba --graph pt --layouts NaivePTsk --points 1280x720x64 \
      --time 2s --workgroup 128
    bench_rows $bin "r$r $bin" --scene sponza --graph pt --layouts $layouts --points 1280x720x16 --time 2s
  done
done
