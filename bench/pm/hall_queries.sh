#!/usr/bin/env bash
# Camera-vertex queries of PPMsk on ModernHall at 1280x720 and r_0 = 0.0038 (about 17 photons a
# query; issue 12's 1 G queries/s target; docs/performance.md, "Photon mapping"), once per
# argument BINARY[:NAME=VALUE,...] (a binary of the bundle and constants; default
# `lightgraph-old lightgraph`, the binary before a change against the one after). `cells`
# stands for the hash grid's cell sizes and bucket counts of "Cell size and bucket count"
# (PM_CELL_SCALE / PM_BUCKETS_PER_PATH 1/1, 1/4, 0.5/1, 0.5/4, 0.75/2, 0.75/4, 0.6/8, with
# today's binary). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin NEW --scene ModernHall` (and, for the default, the
# binary before copied to .gpu/bin/lightgraph-old):
#   bash bench/pm/hall_queries.sh [BINARY[:NAME=VALUE,...]...]
#   bash bench/pm/hall_queries.sh cells
# 60 frames a run after a warm-up run, two interleaved rounds; prints the per-frame counters
# (pm_queries, pm_found) and GPU milliseconds per kernel.
set -uo pipefail
s=.gpu/scenes/ModernHall/staircase2.gltf
# r BINARY ARGS...: one 60-frame render's counters and kernel times on one line.
r() {
  bash .gpu/run.sh "$1" render --scene $s --graph ppm --layout PPMsk --res 1280x720 --frames 60 --set PM_RADIUS=0.0038 \
    "${@:2}" --out /tmp/x.exr 2>&1 | grep -E "GPU time per frame|per frame:" | sed 's/, rays_[a-z]* [0-9.]* [kMG]*//g' | tr '\n' ' '
  echo
}
[ $# -ge 1 ] || set -- lightgraph-old lightgraph
if [ "$*" = cells ]; then
  set --
  for c in "1 1" "1 4" "0.5 1" "0.5 4" "0.75 2" "0.75 4" "0.6 8"; do
    read -r scale buckets <<<"$c"
    set -- "$@" "lightgraph:PM_CELL_SCALE=$scale,PM_BUCKETS_PER_PATH=$buckets"
  done
fi
r lightgraph >/dev/null
for round in 1 2; do
  for variant in "$@"; do
    args=()
    if [[ $variant == *:* ]]; then
      IFS=, read -ra sets <<<"${variant#*:}"
      for v in "${sets[@]}"; do args+=(--set "$v"); done
    fi
    echo -n "round $round $variant: "
    r "${variant%%:*}" "${args[@]}"
  done
done
