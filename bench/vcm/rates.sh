#!/usr/bin/env bash
# Issue 13's two VCM rates at the defaults (docs/performance.md, "A gather a word a thread, a
# cheaper cell hash", and before it "Sorting the cache by a gather, grid keys in the light
# phase, a measured cell scale"): three interleaved rounds of
# LVC-BPTsk and VCMsk on Sponza at 1280x720x1 and of VCMsk (with its default workgroup and with
# 512 threads a workgroup) and LVC-BPTsk on the diffuse box at 256x256 with 64 iterations a
# frame; then, on the glossy box with the sun, LivingRoom, ModernHall and VeachBidir, the cell
# scale VCM measures and VCMsk and VCMmk with it and with PM_CELL_SCALE=1. On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene
# CrytekSponza --scene LivingRoom --scene ModernHall --scene VeachBidir`:
#   bash bench/vcm/rates.sh
# 2 s a point after a 15 s warm-up; prints `bench_rows` lines (bench/common.sh).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
sp() { bench_rows lightgraph "$1 sponza" --time 2s --scene sponza --graph "$2" --layouts "$3" --points 1280x720x1 "${@:4}"; }
box() { bench_rows lightgraph "$1 box" --time 2s --scene cornell-diffuse --graph "$2" --layouts "$3" --points 256x256x64 "${@:4}"; }
bench_rows lightgraph warm --time 15s --scene sponza --graph vcm --layouts VCMsk --points 1280x720x1
for r in 1 2 3; do
  sp "r$r" bpt-lvc LVC-BPTsk
  KERNELS=. sp "r$r" vcm VCMsk
  KERNELS=. box "r$r" vcm VCMsk --set PM_ITERATIONS=64
  box "r$r wg=512" vcm VCMsk --set PM_ITERATIONS=64 --workgroup 512
  box "r$r" bpt-lvc LVC-BPTsk
done
scenes=(cornell-glossy-sun .gpu/scenes/LivingRoom/living-room.gltf .gpu/scenes/ModernHall/staircase2.gltf
  .gpu/scenes/VeachBidir/veach-bidir.gltf)
for scene in "${scenes[@]}"; do
  lg explain --graph vcm --scene "$scene" --res 1280x720 2>&1 | grep "measured PM_CELL_SCALE" | head -1
  bench_rows lightgraph "auto $(basename "$scene")" --time 2s --scene "$scene" --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1
  bench_rows lightgraph "S=1 $(basename "$scene")" --time 2s --scene "$scene" --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1 --set PM_CELL_SCALE=1
done
