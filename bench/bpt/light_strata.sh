#!/usr/bin/env bash
# Light sub-paths whose points on the light are stratified along a Z curve (neighbouring
# sub-paths start close together), the binary before against the one after (docs/performance.md,
# "Photon mapping"). Part `pm`: the photon pass of PPMsk and PPMmk on Sponza and ModernHall at
# 1280x720 (light rays a frame and the GPU ms a frame of the light kernels), and StreamingPTmk3's
# kernels for PT's extension-ray rate on the same scenes. Part `lvc`: `bench` rows (2 s a point)
# of LTsk, LVC-BPTsk, VCMsk and VCMmk on Sponza at 1280x720x1 and of VCMsk on the diffuse box at
# 256x256 with 64 iterations a frame, with their light kernels' GPU ms. On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza --scene ModernHall`
# and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/bpt/light_strata.sh [pm|lvc|all]
# ROUNDS interleaved rounds (default 2), 60 frames a render; both parts by default.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
part=${1:-all}
hall=.gpu/scenes/ModernHall/staircase2.gltf
# kernels BINARY ARGS...: rays a frame and the GPU ms a frame of every kernel.
kernels() {
  bash .gpu/run.sh "$1" render --res 1280x720 --frames 60 "${@:2}" --out /tmp/x.exr 2>&1 \
    | grep -oE "rays_[a-z]* [0-9.]* [kM]?|pm_stored [0-9.]* [kM]?|k[0-9]+_[a-z_0-9]* [0-9.]* ms" | tr '\n' ' '
}
pm_part() {
  kernels lightgraph --scene sponza --graph ppm >/dev/null
  for r in $(seq "${ROUNDS:-2}"); do
    for bin in lightgraph-old lightgraph; do
      for scene in sponza $hall; do
        for layout in PPMsk PPMmk; do
          echo "r$r $bin $(basename $scene) $layout: $(kernels $bin --scene $scene --graph ppm --layout $layout)"
        done
      done
    done
    for scene in sponza $hall; do
      echo "r$r PT $(basename $scene) StreamingPTmk3: $(kernels lightgraph --scene $scene --graph pt --layout StreamingPTmk3)"
    done
  done
}
lvc_part() {
  export KERNELS=light
  for r in $(seq "${ROUNDS:-2}"); do
    for bin in lightgraph-old lightgraph; do
      bench_rows $bin "r$r $bin sponza" --time 2s --scene sponza --graph lt --layouts LTsk --points 1280x720x1
      vcm_rows $bin "r$r $bin"
    done
  done
}
case $part in
  pm) pm_part ;;
  lvc) lvc_part ;;
  all) pm_part; lvc_part ;;
  *) echo "usage: bash bench/bpt/light_strata.sh [pm|lvc|all]" >&2; exit 2 ;;
esac
