#!/usr/bin/env bash
# Photon mapping on the GPU (docs/performance.md, "Photon mapping"): the paper's Table IV
# (WhileQuery against NaiveQuery, whole frames of PPM, SPPM and PBPM with the full hash grid)
# and Table V (PPM's light pass, build and camera pass per structure, photons per frame) on
# Sponza, the glossy Cornell box and the shared scenes LivingRoom, ModernHall and VeachBidir,
# at 1280x720, plus the issue's targets (a full-grid build of 10^7 photons, camera-vertex
# queries per second at about 20 photons a query, photon tracing against path tracing's
# extension rays). Run on the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene LivingRoom --scene ModernHall
# --scene VeachBidir`. Each run prints `render`'s per-frame counters and GPU time per kernel.
#   bash bench/pm/sweep.sh LOG [FRAMES]
set -uo pipefail
log=${1:?usage: bash bench/pm/sweep.sh LOG [FRAMES]}
frames=${2:-10}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
run() { render_summary "$frames" "$@"; }
scenes="sponza cornell-glossy-point .gpu/scenes/LivingRoom/living-room.gltf .gpu/scenes/ModernHall/staircase2.gltf .gpu/scenes/VeachBidir/veach-bidir.gltf"
for s in $scenes; do
  for st in 0 1 3; do run --graph ppm --scene "$s" --set PM_STRUCTURE=$st; done
  for g in ppm sppm pbpm; do
    for w in true false; do run --graph $g --scene "$s" --set PM_WHILE_QUERY=$w; done
  done
done
# Targets: queries at growing radii (photons per query from pm_found / pm_queries), a build of
# about 10^7 photons (3.6 light sub-paths per pixel on Sponza), PT's extension-ray rate.
for r in 0.003 0.006 0.012; do run --graph ppm --scene sponza --set PM_RADIUS=$r; done
run --graph ppm --scene sponza --set PM_LIGHT_PATH_RATIO=3.6
run --graph pt --layout NaivePTsk --scene sponza
run --graph pt --layout StreamingPTmk2 --scene sponza
