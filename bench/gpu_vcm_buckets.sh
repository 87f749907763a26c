#!/usr/bin/env bash
# VCMsk over the hash grid's buckets per light sub-path (PM_BUCKETS_PER_PATH) on Sponza at
# 1280x720 and on the diffuse Cornell box at 256x256 with 64 iterations a frame, against
# LVC-BPTsk (docs/performance.md, "Vertex connection and merging"). On the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza`:
#   bash bench/gpu_vcm_buckets.sh
# 2 s a point, two rounds; prints the run, frames/s, Msamples/s and the camera kernel's GPU ms.
set -uo pipefail
p() { # label bench arguments
  local l=$1
  shift
  bash .gpu/run.sh lightgraph bench --time 2s --out /tmp/vb "$@" >/dev/null 2>&1 || { echo "$l failed"; return; }
  tail -n +2 /tmp/vb/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps fps mem kms; do
    echo "$l,$layout,$fps frames/s,$(awk "BEGIN { printf \"%.1f Msamples/s\", $sps / 1e6 }"),$(echo "$kms" | tr ';' '\n' | grep camera | tr '\n' ' ')"
  done
}
for r in 1 2; do
  p "r$r sponza" --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
  for b in 1 2 4 8; do
    p "r$r sponza buckets $b" --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1 --set PM_BUCKETS_PER_PATH=$b
    p "r$r box buckets $b" --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 --set PM_ITERATIONS=64 \
      --set PM_BUCKETS_PER_PATH=$b
  done
done
