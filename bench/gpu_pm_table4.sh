#!/usr/bin/env bash
# The paper's Table IV (WhileQuery against NaiveQuery, full hash grid) on scenes given as
# arguments (default: LivingRoom and the glossy box with the sun), PPM, SPPM and PBPM at
# 1280x720, 30 frames a run after a warm-up, ROUNDS interleaved rounds (default 3); one line a
# run: the GPU ms a frame of the light kernel, the camera kernel and the split queries' parts.
# On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene LivingRoom`:
#   bash bench/gpu_pm_table4.sh [SCENE...]
set -uo pipefail
source "$(dirname "$0")/gpu_common.sh"
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(.gpu/scenes/LivingRoom/living-room.gltf cornell-glossy-sun)
frame() {
  lg render --res 1280x720 --frames 30 --out /tmp/x.exr "$@" 2>&1 |
    grep -oE "k[0-9]+_(pm_light[a-z_]*|pm_camera[a-z_]*|grid_split_gather) [0-9.]* ms" | tr '\n' ' '
}
frame --graph ppm --scene "${scenes[0]}" >/dev/null
for r in $(seq "${ROUNDS:-3}"); do
  for s in "${scenes[@]}"; do
    for g in ppm sppm pbpm; do
      for w in true false; do
        echo "r$r $s $g WhileQuery=$w: $(frame --graph $g --scene "$s" --set PM_WHILE_QUERY=$w)"
      done
    done
  done
done
