#!/usr/bin/env bash
# The counting sort's scatter with 16-byte vector moves against the binary before (word
# moves), docs/performance.md "Vertex connection and merging". On the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene
# CrytekSponza --scene ModernHall` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/gpu_scatter.sh
# Two rounds of old then new, 2 s a point: VCMsk with 64 iterations a frame at 256x256 on the
# diffuse Cornell box, VCMsk and LVC-BPTsk on Sponza at 1280x720, PPMsk on ModernHall with
# 4.5 light sub-paths per pixel (about 10^7 photons); prints layout, frames/s, samples/s and
# the GPU milliseconds per frame of the scatters (lg_op*_scatter) and of the camera kernel.
set -uo pipefail
hall=.gpu/scenes/ModernHall/staircase2.gltf
point() { # binary, bench arguments
  local bin=$1
  shift
  bash .gpu/run.sh "$bin" bench --time 2s --out /tmp/sc "$@" >/dev/null 2>&1 || { echo "failed: $*"; return; }
  tail -n +2 /tmp/sc/bench.csv | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps fps mem kms; do
    echo "$layout ${w}x${h}x$spp: $fps frames/s, $sps samples/s; $(echo "$kms" | tr ';' '\n' | grep -E 'scatter|camera|count|keys' | tr '\n' ' ')"
  done
}
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    echo "== round $r $bin"
    point $bin --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 --set PM_ITERATIONS=64
    point $bin --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1
    point $bin --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
    point $bin --scene $hall --graph ppm --layouts PPMsk --points 1280x720x1 --set PM_LIGHT_PATH_RATIO=4.5
  done
done
bash .gpu/run.sh lightgraph operators --sizes 10000000 --runs 20 --patterns random --keys random --kernels 2>&1
