#!/usr/bin/env bash
# Frames rendered at once (FRAMES_AT_ONCE) by StreamingBPT and NaiveBPT on the Cornell boxes at
# 512x512x4 (issue 16's StreamingBPT target), and by PT's best layouts at 1280x720x16
# (docs/performance.md, "Frames at once"). On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_bpt_at_once.sh
# Prints scene, graph, FRAMES_AT_ONCE, threads, layout, point, Msamples/s wall-clock, Mrays/s
# wall-clock and of GPU time.
set -uo pipefail
point() { # scene graph layouts points N [threads]
  bash .gpu/run.sh lightgraph bench --scene "$1" --graph "$2" --layouts "$3" --points "$4" --time 3s \
    --set FRAMES_AT_ONCE="$5" ${6:+--threads $6} --out /tmp/ba >/dev/null 2>&1 || { echo "$*: failed"; return; }
  tail -n +2 /tmp/ba/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps rest; do
    echo "$1,$2,N=$5,threads=${6:-layout},$layout,${w}x${h}x$spp,$(awk "BEGIN { printf \"%.1f Msamples/s,%.0f,%.0f Mrays/s\", $sps / 1e6, $rps / 1e6, $grps / 1e6 }")"
  done
}
for scene in cornell-glossy-point cornell-diffuse; do
  for n in 1 4 16; do
    point $scene bpt-streaming StreamingBPT 512x512x4 $n
    point $scene bpt-naive NaiveBPT,NaiveBPTmk 512x512x4 $n
  done
  point $scene bpt-streaming StreamingBPT 512x512x4 16 1048576
done
for n in 1 4; do
  point sponza pt StreamingPTmk1,StreamingPTmk2 1280x720x16 $n
  point cornell-mitsuba pt NaivePTsk,RegenerationPTsk,StreamingPTmk1 1280x720x16 $n
done
