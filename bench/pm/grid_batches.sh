#!/usr/bin/env bash
# Hash grid gathers that read a bucket's entries four at a time, the binary before against the
# one after (docs/performance.md, "Photon mapping" and "Vertex connection and merging"):
# PPMsk's camera kernel on ModernHall at 1280x720 with r_0 0.0038 and 0.0041 (about 17 and 20
# photons a query) and with no photon stored (PM_MEASURING: the queries' other costs), SPPMsk
# and WhileQuery; then VCMsk and VCMmk on Sponza against LVC-BPTsk, and VCMsk on the diffuse
# box at 256x256 with 64 iterations a frame. On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza --scene ModernHall`
# and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/pm/grid_batches.sh [BINARY...]
# The binaries named (default lightgraph-old lightgraph; the first the one before) run in turn.
# Also used for commit 3671084 (the photons' positions in an array of their own and a query's 8
# bucket ranges read at once; slower, reverted in cd866e5):
#   bash bench/pm/grid_batches.sh lightgraph-head lightgraph-pos lightgraph-new
# Two interleaved rounds (60 frames a render, 2 s a bench point). The VCM lines were measured
# with the batched read in VCM's gather too (commit 1c9aa02); VCM reads one entry at a time
# again since, so with later binaries they compare like with like.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
hall=.gpu/scenes/ModernHall/staircase2.gltf
# camera BINARY GRAPH LAYOUT ARGS...: photons found, queries, and the GPU ms a frame of the
# camera kernel and of the grid's build kernels.
camera() {
  bash .gpu/run.sh "$1" render --scene $hall --graph "$2" --layout "$3" --res 1280x720 --frames 60 "${@:4}" \
    --out /tmp/x.exr 2>&1 | grep -oE "pm_found [0-9.]* [kM]?|pm_queries [0-9.]* [kM]?|k[0-9]+_(pm_camera|grid)[a-z_]* [0-9.]* ms|lg_op[0-9]+_[a-z0-9]* [0-9.]* ms" | tr '\n' ' '
}
[ $# -ge 1 ] || set -- lightgraph-old lightgraph
bins=("$@")
camera "${bins[0]}" ppm PPMsk >/dev/null
export KERNELS=camera
for r in 1 2; do
  for bin in "${bins[@]}"; do
    for radius in 0.0038 0.0041; do
      echo "r$r $bin PPMsk r_0 $radius: $(camera $bin ppm PPMsk --set PM_RADIUS=$radius)"
      echo "r$r $bin PPMsk r_0 $radius no photon: $(camera $bin ppm PPMsk --set PM_RADIUS=$radius --set PM_MEASURING=true)"
    done
    echo "r$r $bin SPPMsk r_0 0.0038: $(camera $bin sppm SPPMsk --set PM_RADIUS=0.0038)"
    echo "r$r $bin PPMsk WhileQuery r_0 0.0038: $(camera $bin ppm PPMsk --set PM_RADIUS=0.0038 --set PM_WHILE_QUERY=true)"
    vcm_rows $bin "r$r $bin"
  done
done
