#!/usr/bin/env bash
# Where PPMsk's camera kernel goes on VeachBidir (a lamp under a shade; its photons are dense in places):
# r_0 = 0.008 (about 17 photons a query) with the defaults, more buckets, smaller cells, both,
# WhileQuery, the kD-tree and the rectified stochastic grid, and with no photon stored. On the
# GPU machine from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh
# --scene VeachBidir`:
#   bash bench/pm/dense.sh [BINARY]
# 60 frames a render, two interleaved rounds.
set -uo pipefail
source "$(dirname "$0")/../common.sh"
bin=${1:-lightgraph}
camera() { ppm_camera "$bin" --scene .gpu/scenes/VeachBidir/veach-bidir.gltf --set PM_RADIUS=0.008 "$@"; }
camera >/dev/null
for r in 1 2; do
  for sets in "" "PM_BUCKETS_PER_PATH=4" "PM_CELL_SCALE=0.5" "PM_CELL_SCALE=0.5 PM_BUCKETS_PER_PATH=4" \
    "PM_WHILE_QUERY=true" "PM_STRUCTURE=3" "PM_STRUCTURE=1" "PM_MEASURING=true"; do
    args=()
    for s in $sets; do args+=(--set "$s"); done
    echo "r$r ${sets:-defaults}: $(camera "${args[@]}")"
  done
done
