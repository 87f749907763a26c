#!/usr/bin/env bash
# The paper's Table IV (WhileQuery against NaiveQuery, full hash grid) on scenes given as
# arguments (default: LivingRoom and the glossy box with the sun), PPMsk, SPPMsk and PBPMsk at
# 1280x720 (`ppm_camera`: 60 frames a run; the session that added this script ran 30), after a
# warm-up, ROUNDS interleaved rounds (default 3); one line a run: counters, and the GPU ms a
# frame of the light and camera kernels, the split queries' parts and the operators.
# On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene LivingRoom`:
#   bash bench/pm/table4.sh [SCENE...]
set -uo pipefail
source "$(dirname "$0")/../common.sh"
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(.gpu/scenes/LivingRoom/living-room.gltf cornell-glossy-sun)
ppm_camera lightgraph --scene "${scenes[0]}" >/dev/null
for r in $(seq "${ROUNDS:-3}"); do
  for s in "${scenes[@]}"; do
    for g in ppm sppm pbpm; do
      for w in true false; do
        echo "r$r $s $g WhileQuery=$w: $(PM_GRAPH=$g PM_LAYOUT=${g^^}sk ppm_camera lightgraph --scene "$s" --set PM_WHILE_QUERY=$w)"
      done
    done
  done
done
