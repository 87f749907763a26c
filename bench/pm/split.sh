#!/usr/bin/env bash
# Queries split over threads (issue 12; shaders/pm/grid.wgsl): PPMsk's camera kernel and the
# split parts' kernel at 1280x720 on five scenes at about 20 photons a query, once per argument
# BINARY[:NAME=VALUE,...] (a binary of the bundle and constants, e.g. split thresholds and part
# sizes PM_SPLIT_ENTRIES and PM_SPLIT_CHUNK; PM_SPLIT_ENTRIES=0 never splits); then SPPMsk and
# PBPMsk on VeachBidir (photons dense under the lamp's shade) with and without splitting (the
# defaults), with the first argument's binary. On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene ModernHall --scene VeachBidir`:
#   bash bench/pm/split.sh lightgraph-old lightgraph:PM_SPLIT_ENTRIES=0 lightgraph
# 60 frames a render, ROUNDS interleaved rounds (default 2).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
runs=(
  "cornell-diffuse 0.0068"
  "cornell-glossy-point 0.0075"
  ".gpu/scenes/ModernHall/staircase2.gltf 0.0041"
  "sponza 0.052"
  ".gpu/scenes/VeachBidir/veach-bidir.gltf 0.008"
)
first=${1%%:*}
ppm_camera "$first" --scene cornell-glossy-point >/dev/null
for r in $(seq "${ROUNDS:-2}"); do
  for run in "${runs[@]}"; do
    read -r scene radius <<<"$run"
    for variant in "$@"; do
      args=()
      if [[ $variant == *:* ]]; then
        IFS=, read -ra sets <<<"${variant#*:}"
        for s in "${sets[@]}"; do args+=(--set "$s"); done
      fi
      echo "r$r $scene $variant: $(ppm_camera "${variant%%:*}" --scene "$scene" --set PM_RADIUS="$radius" "${args[@]}")"
    done
  done
  for graph in sppm:SPPMsk pbpm:PBPMsk; do
    for entries in 0 default; do
      sets=()
      [ $entries = 0 ] && sets=(--set PM_SPLIT_ENTRIES=0)
      echo "r$r VeachBidir ${graph#*:} $entries: $(PM_GRAPH=${graph%:*} PM_LAYOUT=${graph#*:} ppm_camera "$first" \
        --scene .gpu/scenes/VeachBidir/veach-bidir.gltf --set PM_RADIUS=0.008 "${sets[@]}")"
    done
  done
done
