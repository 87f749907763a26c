#!/usr/bin/env bash
# Shader variants A/B: the bundled binary with its own shaders against graph folders that carry
# their own copies of the graphs and of some WGSL files (a variant is DIR/pt.ron, DIR/bpt-lvc.ron,
# DIR/vcm.ron with DIR/shaders/lib/*.wgsl; no rebuild), two interleaved rounds, 2 s a point:
# sponza-mitsuba (16 frames at once, a pool of 2^23), Sponza's StreamingPTmk2, LVC-BPTsk and VCMsk,
# the diffuse box's VCMsk at 256x256 with 64 iterations a frame, and the Cornell box's NaivePTsk.
# On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   VARIANTS="exp/a exp/b" bash bench/ab/shader_variants.sh
set -uo pipefail
source "$(dirname "$0")/../common.sh"
# rows LABEL GRAPH_PREFIX GRAPH_SUFFIX: the runs of one variant.
rows() {
  local l=$1 pre=$2 suf=$3
  bench_rows lightgraph "$l sponza-mitsuba, 16 at once, 2^23" --time 2s --scene sponza-mitsuba --graph "${pre}pt$suf" \
    --layouts StreamingPTmk2 --points 1280x720x16 --set FRAMES_AT_ONCE=16 --threads 8388608
  bench_rows lightgraph "$l sponza" --time 2s --scene sponza --graph "${pre}pt$suf" --points 1280x720x16 --layouts StreamingPTmk2
  bench_rows lightgraph "$l sponza" --time 2s --scene sponza --graph "${pre}bpt-lvc$suf" --layouts LVC-BPTsk --points 1280x720x1
  bench_rows lightgraph "$l sponza" --time 2s --scene sponza --graph "${pre}vcm$suf" --layouts VCMsk --points 1280x720x1
  bench_rows lightgraph "$l box" --time 2s --scene cornell-diffuse --graph "${pre}vcm$suf" --layouts VCMsk \
    --points 256x256x64 --set PM_ITERATIONS=64
  bench_rows lightgraph "$l box" --time 2s --scene cornell-mitsuba --graph "${pre}pt$suf" --layouts NaivePTsk --points 1280x720x16
}
bench_rows lightgraph warm --time 2s --scene sponza --graph pt --layouts StreamingPTmk2 --points 1280x720x16 >/dev/null
for r in 1 2; do
  rows "r$r shipped" "" ""
  for v in ${VARIANTS:?VARIANTS names the graph folders}; do rows "r$r $v" "${v%/}/" .ron; done
done
