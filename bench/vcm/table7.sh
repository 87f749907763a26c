#!/usr/bin/env bash
# Table VII (VCMsk against VCMmk, docs/performance.md) with binaries of the bundle against each
# other (default: .gpu/bin/lightgraph-old, the build before a change, and lightgraph): `bench
# --time 2s` of both layouts at 1280x720x1 on the glossy box with the sun, LivingRoom,
# ModernHall, VeachBidir and Sponza, with the camera and gather kernels' GPU ms a frame; ROUNDS
# interleaved rounds (default 2). On the GPU machine from the repo root with carry [".gpu"]
# after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza --scene LivingRoom
# --scene ModernHall --scene VeachBidir` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/vcm/table7.sh [BINARY...]
set -uo pipefail
source "$(dirname "$0")/../common.sh"
bins=("$@")
[ ${#bins[@]} -gt 0 ] || bins=(lightgraph-old lightgraph)
export KERNELS="camera|gather"
scenes=(cornell-glossy-sun .gpu/scenes/LivingRoom/living-room.gltf .gpu/scenes/ModernHall/staircase2.gltf
  .gpu/scenes/VeachBidir/veach-bidir.gltf sponza)
for r in $(seq "${ROUNDS:-2}"); do
  for bin in "${bins[@]}"; do
    for scene in "${scenes[@]}"; do
      bench_rows "$bin" "r$r $bin $(basename "$scene")" --time 2s --scene "$scene" --graph vcm --layouts VCMsk,VCMmk \
        --points 1280x720x1
    done
  done
done
