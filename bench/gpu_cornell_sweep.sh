#!/usr/bin/env bash
# PT's single-kernel layouts on the Cornell box (cornell-mitsuba, 1280x720x16) over the BVH and
# the workgroup size, and the BVH build's A/B against the binary before it (docs/performance.md,
# "BVH build quality"). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin BIN --scene CrytekSponza` and the binary before the
# BVH change copied to .gpu/bin/lightgraph-old:
#   bash bench/gpu_cornell_sweep.sh
# 2 s a point; prints binary, scene, layout, BVH, workgroup, Gsamples/s and Mrays/s wall-clock.
set -uo pipefail
point() { # binary scene layouts bvh workgroup
  bash .gpu/run.sh "$1" bench --scene "$2" --graph pt --layouts "$3" --points 1280x720x16 --time 2s \
    --bvh "$4" ${5:+--workgroup $5} --out /tmp/cs >/dev/null 2>&1 || { echo "$*: failed"; return; }
  tail -n +2 /tmp/cs/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps rest; do
    echo "$1,$2,$layout,$4,workgroup=${5:-default},$(awk "BEGIN { printf \"%.3f Gsamples/s,%.0f Mrays/s\", $sps / 1e9, $rps / 1e6 }")"
  done
}
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    point $bin cornell-mitsuba NaivePTsk,RegenerationPTsk auto
    point $bin sponza NaivePTsk,StreamingPTmk1,StreamingPTmk2,RegenerationPTsk auto
  done
done
for bvh in bvh2 cwbvh; do
  for wg in 32 64 128 256; do point lightgraph cornell-mitsuba NaivePTsk,RegenerationPTsk $bvh $wg; done
done
