#!/usr/bin/env bash
# Queue and compaction appends, one atomic per subgroup against one per item (issue 16,
# item 3; docs/performance.md, "Subgroup-aggregated appends"). On the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/engine/subgroups.sh OUT_DIR
# (1) the same image: WavefrontPT and StreamingBPT on Sponza, 8 frames of one seed per item
# and per subgroup; the second run's RMSE against the first must be float rounding (about
# 1e-7 of the radiance, far below the noise), with the same ray count;
# (2) rates of the layouts that append (PT's at 1, 4 and 16 samples per pixel per frame, light
# tracing's and BPT's at 1) at 1280x720, 2 s a point, in two interleaved rounds of per
# subgroup then --no-subgroups (the H100's clocks drift between runs of one call). Graphs
# with operators (LVC-BPT, VCM, photon mapping) are left out: --no-subgroups also changes
# their scans. Writes OUT_DIR/subgroups.md (the bench folders stay in /tmp).
set -uo pipefail
out=${1:?usage: bash bench/engine/subgroups.sh OUT_DIR}
mkdir -p "$out"
log=$out/subgroups.md
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1 | tee "$log"
lg() { bash .gpu/run.sh lightgraph "$@"; }
same_image() { # $1 = graph, $2 = layout
  local common=(--scene sponza --graph "$1" --layout "$2" --res 640x360 --frames 8 --seed 3)
  echo "### same image: $1 $2" >>"$log"
  lg render "${common[@]}" --no-subgroups --out /tmp/gpu-sg/per-item.exr 2>&1 | grep -E "^per frame:|rror" >>"$log"
  lg render "${common[@]}" --out /tmp/gpu-sg/per-subgroup.exr --reference /tmp/gpu-sg/per-item.exr 2>&1 |
    grep -E "^per frame:|rror" >>"$log"
}
bench() { # $1 = title, then bench arguments; appends the rate table
  local title=$1; shift
  echo "### $title" >>"$log"
  rm -rf /tmp/gpu-sg-bench # bench refuses a folder holding an earlier bench
  lg bench "$@" --out /tmp/gpu-sg-bench >/dev/null 2>/tmp/gpu-sg.err || tail -3 /tmp/gpu-sg.err | tee -a "$log"
  sed -n '/^| layout | [0-9]/,/^$/p' /tmp/gpu-sg-bench/bench.md >>"$log"
}
mkdir -p /tmp/gpu-sg
same_image pt WavefrontPT
same_image bpt-streaming StreamingBPT
pt_layouts=NaivePTmk,RegenerationPTmk2,StreamingPTmk1,StreamingPTmk2,StreamingPTmk3,WavefrontPT
for round in 1 2; do
  for flag in "" --no-subgroups; do
    name=${flag:-subgroups}
    bench "pt round $round $name" --scene sponza --graph pt --layouts $pt_layouts --time 2s \
      --points 1280x720x1,1280x720x4,1280x720x16 $flag
    for g in lt bpt-naive bpt-streaming; do
      bench "$g round $round $name" --scene sponza --graph $g --layouts all --time 2s --points 1280x720x1 $flag
    done
  done
done
cat "$log"
