#!/usr/bin/env bash
# Issue 12's camera-vertex queries per second at about 20 photons a query on five scenes:
# PPMsk's camera kernel at 1280x720 (screen order: 8x8 tiles), each scene at the radii r_0
# listed below (around 20 photons a query over 60 frames), once per variant: each argument is a
# list of NAME=VALUE constants ("-" for the defaults). With PM_MEASURING=true no photon is
# stored, so the camera kernel's time less that run's is the gathers'. On the GPU machine from
# the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza
# --scene ModernHall --scene VeachBidir`:
#   bash bench/pm/queries.sh - PM_MEASURING=true
# 60 frames a render, ROUNDS interleaved rounds (default 2); BIN names the bundle's binary.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
camera() { ppm_camera "${BIN:-lightgraph}" "$@"; }
runs=(
  "cornell-diffuse 0.0058 0.0068"
  "cornell-glossy-point 0.0065 0.0075"
  ".gpu/scenes/ModernHall/staircase2.gltf 0.0041"
  "sponza 0.045 0.052"
  ".gpu/scenes/VeachBidir/veach-bidir.gltf 0.008 0.0095"
)
camera --scene cornell-glossy-point >/dev/null
for r in $(seq "${ROUNDS:-2}"); do
  for run in "${runs[@]}"; do
    read -r scene radii <<<"$run"
    for radius in $radii; do
      for variant in "$@"; do
        args=()
        [ "$variant" = - ] || for s in $variant; do args+=(--set "$s"); done
        echo "r$r $scene r_0 $radius $variant: $(camera --scene "$scene" --set PM_RADIUS="$radius" "${args[@]}")"
      done
    done
  done
done
