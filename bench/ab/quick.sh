#!/usr/bin/env bash
# Two binaries of the bundle against each other, quickly (about 70 s a binary a round): PT on
# Sponza (NaivePTsk, StreamingPTmk2) and NaivePTsk on cornell-mitsuba at 1280x720x16, and issue
# 13's VCM rows (`vcm_rows`: LVC-BPTsk, VCMsk and VCMmk on Sponza, VCMsk on the 256x256 box with
# 64 iterations a frame), 2 s a point, ROUNDS interleaved rounds (default 2; the first often
# cold). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza` and the binary before copied
# to .gpu/bin/lightgraph-old:
#   bash bench/ab/quick.sh [OLD NEW]
set -uo pipefail
source "$(dirname "$0")/../common.sh"
old=${1:-lightgraph-old} new=${2:-lightgraph}
for r in $(seq "${ROUNDS:-2}"); do
  for bin in "$old" "$new"; do
    bench_rows "$bin" "r$r $bin sponza" --time 2s --scene sponza --graph pt --layouts NaivePTsk,StreamingPTmk2 \
      --points 1280x720x16
    bench_rows "$bin" "r$r $bin box" --time 2s --scene cornell-mitsuba --graph pt --layouts NaivePTsk --points 1280x720x16
    vcm_rows "$bin" "r$r $bin"
  done
done
