#!/usr/bin/env bash
# The counting sort's scatter with 16-byte vector moves against the binary before (word
# moves), docs/performance.md "Vertex connection and merging". On the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene
# CrytekSponza --scene ModernHall` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/engine/scatter.sh
# Two rounds of old then new, 2 s a point: VCMsk with 64 iterations a frame at 256x256 on the
# diffuse Cornell box, VCMsk and LVC-BPTsk on Sponza at 1280x720, PPMsk on ModernHall with
# 4.5 light sub-paths per pixel (about 10^7 photons); prints `bench_rows` lines
# (bench/common.sh) with the scatters', count's, keys' and camera kernel's GPU ms a frame.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
hall=.gpu/scenes/ModernHall/staircase2.gltf
export KERNELS='scatter|camera|count|keys'
for r in 1 2; do
  for bin in lightgraph-old lightgraph; do
    echo "== round $r $bin"
    bench_rows $bin box --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk --points 256x256x64 --set PM_ITERATIONS=64
    bench_rows $bin sponza --time 2s --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1
    bench_rows $bin sponza --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
    bench_rows $bin hall --time 2s --scene $hall --graph ppm --layouts PPMsk --points 1280x720x1 --set PM_LIGHT_PATH_RATIO=4.5
  done
done
lg operators --sizes 10000000 --runs 20 --patterns random --keys random --kernels 2>&1
