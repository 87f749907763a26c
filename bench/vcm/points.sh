#!/usr/bin/env bash
# VCM with binaries of the bundle against each other (default: .gpu/bin/lightgraph-old, the
# build before a change, and lightgraph): 100-frame renders of VCMsk and VCMmk on the diffuse
# box at 256x256 with 64 iterations a frame and on Sponza at 1280x720 (Msamples/s and the GPU
# ms a frame of the camera, gather and operator kernels), then `bench --time 3s` of VCMsk on the
# box and LVC-BPTsk on Sponza; ROUNDS interleaved rounds (default 3, the first often cold). On
# the GPU machine from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh
# --bin NEW --scene CrytekSponza` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/vcm/points.sh [BINARY...]
set -uo pipefail
source "$(dirname "$0")/../common.sh"
bins=("$@")
[ ${#bins[@]} -gt 0 ] || bins=(lightgraph-old lightgraph)
# vcm_render BINARY LABEL ARGS...: one 100-frame render's rate and kernel times on one line.
vcm_render() {
  local bin=$1 label=$2
  shift 2
  echo "$label: $(bash .gpu/run.sh "$bin" render --graph vcm --frames 100 --out /tmp/x.exr "$@" 2>&1 |
    grep -oE "[0-9.]+ Msamples/s|k[0-9]+_[a-z_]*(camera|gather)[a-z_]* [0-9.]+ ms|lg_op[0-9]+_scatter [0-9.]+ ms" | tr '\n' ' ')"
}
for r in $(seq "${ROUNDS:-3}"); do
  for bin in "${bins[@]}"; do
    for layout in VCMsk VCMmk; do
      vcm_render "$bin" "r$r $bin box $layout" --layout "$layout" --scene cornell-diffuse --res 256x256 --spp 64 \
        --set PM_ITERATIONS=64
      vcm_render "$bin" "r$r $bin sponza $layout" --layout "$layout" --scene sponza --res 1280x720 --spp 1
    done
    bench_rows "$bin" "r$r $bin box" --time 3s --scene cornell-diffuse --graph vcm --layouts VCMsk \
      --points 256x256x64 --set PM_ITERATIONS=64
    bench_rows "$bin" "r$r $bin sponza" --time 3s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
  done
done
