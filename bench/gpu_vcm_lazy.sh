#!/usr/bin/env bash
# VCM's merge BSDF set up at the first cached vertex found, against the binary before
# (docs/performance.md, "Vertex connection and merging"). On the GPU machine from the repo
# root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza`
# and the binary before the change copied to .gpu/bin/lightgraph-old:
#   bash bench/gpu_vcm_lazy.sh
# Two rounds of old then new (the first warms the clocks), 2 s a point: VCMsk and VCMmk
# against LVC-BPTsk on Sponza at 1280x720, VCMsk at 256x256 on the diffuse Cornell box. Prints
# layout, frames, seconds, samples/s and GPU ms per kernel (frames/s at 256x256).
set -uo pipefail
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    echo "== round $r $bin"
    bash .gpu/run.sh $bin bench --scene sponza --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1 --time 2s \
      --out /tmp/v >/dev/null 2>&1
    cut -d, -f1,6,7,11,14 /tmp/v/bench.csv | tail -n +2
    bash .gpu/run.sh $bin bench --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1 --time 2s \
      --out /tmp/l >/dev/null 2>&1
    cut -d, -f1,6,7,11,14 /tmp/l/bench.csv | tail -n +2
    bash .gpu/run.sh $bin bench --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x1 --time 2s \
      --out /tmp/c >/dev/null 2>&1
    cut -d, -f1,6,7,11,12 /tmp/c/bench.csv | tail -n +2
  done
done
