#!/usr/bin/env bash
# VCMsk and LVC-BPTsk on Sponza at 1280x720 over their pool of persistent threads and their
# workgroup size (docs/performance.md, "Vertex connection and merging"). On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene
# CrytekSponza`:
#   bash bench/gpu_vcm_occupancy.sh
# 2 s a point; prints graph, threads, workgroup, Msamples/s and the camera kernel's GPU ms.
set -uo pipefail
point() { # graph layout threads workgroup
  bash .gpu/run.sh lightgraph bench --scene sponza --graph "$1" --layouts "$2" --points 1280x720x1 --time 2s \
    ${3:+--threads $3} ${4:+--workgroup $4} --out /tmp/vo >/dev/null 2>&1 || { echo "$*: failed"; return; }
  tail -n +2 /tmp/vo/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps fps mem kms; do
    echo "$1,threads=${3:-default},workgroup=${4:-default},$(awk "BEGIN { printf \"%.1f Msamples/s\", $sps / 1e6 }"),$(echo "$kms" | tr ';' '\n' | grep camera | tr '\n' ' ')"
  done
}
for g in "vcm VCMsk" "bpt-lvc LVC-BPTsk"; do
  set -- $g
  point $1 $2
  for t in 131072 262144 524288; do point $1 $2 $t; done
  for w in 32 64 128 256; do point $1 $2 "" $w; done
done
