#!/usr/bin/env bash
# Which BVH suits which layout (issue 16, item 4; docs/performance.md, "Which BVH in which
# layout"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/traversal/bvh.sh OUT_DIR
# (1) every named PT layout on Sponza (1 to 64 samples per pixel per frame) and on Mitsuba's
# Cornell box (1 and 16) at 1280x720, 1 s a point, with the CWBVH and with the BVH2;
# (2) every named layout of the other graphs on Sponza at 1280x720x1, 2 s a point, in two
# interleaved rounds (the H100's clocks drift between runs of one call); PT's NaivePT layouts
# again in three. Writes the tables to OUT_DIR/bvh.md (the bench folders stay in /tmp).
set -uo pipefail
out=${1:?usage: bash bench/traversal/bvh.sh OUT_DIR}
mkdir -p "$out"
log=$out/bvh.md
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1 | tee "$log"
bench() { # $1 = title, then bench arguments; appends the rate table
  local title=$1; shift
  echo "### $title" >>"$log"
  rm -rf /tmp/gpu-bvh # bench refuses a folder holding an earlier bench
  bash .gpu/run.sh lightgraph bench "$@" --out /tmp/gpu-bvh >/dev/null 2>/tmp/gpu-bvh.err || tail -3 /tmp/gpu-bvh.err | tee -a "$log"
  sed -n '/^| layout | [0-9]/,/^$/p' /tmp/gpu-bvh/bench.md >>"$log"
}
for bvh in cwbvh bvh2; do
  bench "pt sponza $bvh" --scene sponza --graph pt --layouts all --bvh $bvh --time 1s \
    --points 1280x720x1,1280x720x4,1280x720x16,1280x720x64
  bench "pt cornell-mitsuba $bvh" --scene cornell-mitsuba --graph pt --layouts all --bvh $bvh --time 1s \
    --points 1280x720x1,1280x720x16
done
for round in 1 2; do
  for bvh in cwbvh bvh2; do
    for g in ppm sppm pbpm; do
      bench "$g sponza $bvh round $round" --scene sponza --graph $g --set PM_RADIUS=0.03 --layouts all --bvh $bvh --time 2s --points 1280x720x1
    done
    for g in lt bpt-naive bpt-streaming bpt-lvc; do
      bench "$g sponza $bvh round $round" --scene sponza --graph $g --layouts all --bvh $bvh --time 2s --points 1280x720x1
    done
    bench "pt NaivePT sponza $bvh round $round" --scene sponza --graph pt --layouts NaivePTmk,NaivePTsk --bvh $bvh --time 2s --points 1280x720x4,1280x720x16
  done
done
cat "$log"
