#!/usr/bin/env bash
# The hash grid's cell size and bucket count against the gather's time (docs/performance.md,
# "Photon mapping"): PPMsk on ModernHall at 1280x720 and r_0 = 0.0038 (about 17 photons a
# query), 60 frames a run after one warm-up run, two interleaved rounds. On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene ModernHall`:
#   bash bench/gpu_pm_cells.sh
s=.gpu/scenes/ModernHall/staircase2.gltf
r() { bash .gpu/run.sh lightgraph render --scene $s --graph ppm --layout PPMsk --res 1280x720 --frames 60 --set PM_RADIUS=0.0038 "$@" --out /tmp/x.exr 2>&1 | grep -E "GPU time per frame|per frame:" | sed 's/, rays_[a-z]* [0-9.]* [kMG]*//g' | tr '\n' ' '; echo; }
r >/dev/null
for round in 1 2; do for c in "1 1" "1 4" "0.5 1" "0.5 4" "0.75 2" "0.75 4" "0.6 8"; do set -- $c; echo -n "round $round scale $1 buckets $2: "; r --set PM_CELL_SCALE=$1 --set PM_BUCKETS_PER_PATH=$2; done; done
