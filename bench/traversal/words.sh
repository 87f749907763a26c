#!/usr/bin/env bash
# Nodes and primitives loaded as 16-byte words (docs/performance.md, "Nodes and primitives loaded
# as 16-byte words"): the binary BEFORE (copied into .gpu/bin) against today's, two interleaved
# rounds, 2 s a point. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   BEFORE=lightgraph-old bash bench/traversal/words.sh
# A graph folder with its own shaders (GRAPHS=exp/v/, the graphs as exp/v/pt.ron etc.) adds a
# third row per round: today's binary with those shaders.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
# rows BINARY LABEL GRAPH_PREFIX GRAPH_SUFFIX: every run of the A/B.
rows() {
  local b=$1 l=$2 pre=$3 suf=$4
  bench_rows "$b" "$l sponza" --time 2s --scene sponza --graph "${pre}pt$suf" --points 1280x720x16 \
    --layouts StreamingPTmk2,NaivePTsk,RegenerationPTsk,StreamingPTmk1,WavefrontPT
  bench_rows "$b" "$l sponza-mitsuba, 16 at once, 2^23" --time 2s --scene sponza-mitsuba --graph "${pre}pt$suf" \
    --layouts StreamingPTmk2 --points 1280x720x16 --set FRAMES_AT_ONCE=16 --threads 8388608
  bench_rows "$b" "$l sponza" --time 2s --scene sponza --graph "${pre}bpt-lvc$suf" --layouts LVC-BPTsk,LVC-BPTmk --points 1280x720x1
  bench_rows "$b" "$l sponza" --time 2s --scene sponza --graph "${pre}vcm$suf" --layouts VCMsk,VCMmk --points 1280x720x1
  bench_rows "$b" "$l box" --time 2s --scene cornell-diffuse --graph "${pre}vcm$suf" --layouts VCMsk --points 256x256x64 \
    --set PM_ITERATIONS=64
  bench_rows "$b" "$l box" --time 2s --scene cornell-mitsuba --graph "${pre}pt$suf" --layouts NaivePTsk,RegenerationPTsk \
    --points 1280x720x16
}
bench_rows lightgraph warm --time 2s --scene sponza --graph pt --layouts StreamingPTmk2 --points 1280x720x16 >/dev/null
for r in 1 2; do
  rows "${BEFORE:?BEFORE names the binary before}" "r$r before" "" ""
  rows lightgraph "r$r after" "" ""
  [ -n "${GRAPHS:-}" ] && rows lightgraph "r$r $GRAPHS" "$GRAPHS" .ron
done
