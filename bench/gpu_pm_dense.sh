#!/usr/bin/env bash
# Where PPMsk's camera kernel goes on VeachBidir (its lamp's shade gathers photons densely):
# r_0 = 0.008 (about 17 photons a query) with the defaults, more buckets, smaller cells, both,
# WhileQuery, the kD-tree and the rectified stochastic grid, and with no photon stored. On the
# GPU machine from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh
# --scene VeachBidir`:
#   bash bench/gpu_pm_dense.sh [BINARY]
# 60 frames a render, two interleaved rounds.
set -uo pipefail
bin=${1:-lightgraph}
camera() {
  bash .gpu/run.sh "$bin" render --scene .gpu/scenes/VeachBidir/veach-bidir.gltf --graph ppm --layout PPMsk \
    --res 1280x720 --frames 60 --set PM_RADIUS=0.008 "$@" --out /tmp/x.exr 2>&1 |
    grep -oE "pm_found [0-9.]* [kM]?|pm_queries [0-9.]* [kM]?|k[0-9]+_pm_camera[a-z_]* [0-9.]* ms" | tr '\n' ' '
}
camera >/dev/null
for r in 1 2; do
  for sets in "" "PM_BUCKETS_PER_PATH=4" "PM_CELL_SCALE=0.5" "PM_CELL_SCALE=0.5 PM_BUCKETS_PER_PATH=4" \
    "PM_WHILE_QUERY=true" "PM_STRUCTURE=3" "PM_STRUCTURE=1" "PM_MEASURING=true"; do
    args=()
    for s in $sets; do args+=(--set "$s"); done
    echo "r$r ${sets:-defaults}: $(camera "${args[@]}")"
  done
done
