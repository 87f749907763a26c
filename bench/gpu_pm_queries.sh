#!/usr/bin/env bash
# Camera-vertex queries per second of PPMsk on ModernHall at 1280x720 and r_0 = 0.0038 (about
# 17 photons a query; issue 12's 1 G queries/s target), the binary before a change against the
# one after (docs/performance.md, "Photon mapping"). On the GPU machine from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene ModernHall` and the
# binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/gpu_pm_queries.sh
# 60 frames a run after a warm-up run, two interleaved rounds; prints the per-frame counters
# (pm_queries, pm_found) and GPU milliseconds per kernel.
s=.gpu/scenes/ModernHall/staircase2.gltf
r() { bash .gpu/run.sh "$1" render --scene $s --graph ppm --layout PPMsk --res 1280x720 --frames 60 --set PM_RADIUS=0.0038 --out /tmp/x.exr 2>&1 | grep -E "GPU time per frame|per frame:" | sed 's/, rays_[a-z]* [0-9.]* [kMG]*//g' | tr '\n' ' '; echo; }
r lightgraph >/dev/null
for round in 1 2; do for bin in lightgraph-old lightgraph; do echo -n "round $round $bin: "; r $bin; done; done
