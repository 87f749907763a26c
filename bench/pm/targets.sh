#!/usr/bin/env bash
# Photon mapping's second sweep on the GPU machine (docs/performance.md, "Photon mapping"):
# after a warm-up (the H100's clocks ramp up over the first seconds), 30 frames per run at
# 1280x720 of WhileQuery against NaiveQuery and of each structure, a full-grid build of about
# 10^7 photons (4.5 light sub-paths per pixel on ModernHall) and path tracing's ray rate on
# the same scene. Run from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene ModernHall --scene VeachBidir`.
#   bash bench/pm/targets.sh LOG
set -uo pipefail
log=${1:?usage: bash bench/pm/targets.sh LOG}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
run() { render_summary 30 "$@"; }
lg render --graph pt --scene sponza --res 1280x720 --frames 200 --out "$out/warm.exr" >/dev/null 2>&1
hall=.gpu/scenes/ModernHall/staircase2.gltf
veach=.gpu/scenes/VeachBidir/veach-bidir.gltf
for g in ppm sppm pbpm; do for w in true false; do run --graph $g --scene $hall --set PM_WHILE_QUERY=$w; done; done
for st in 1 3; do run --graph ppm --scene $hall --set PM_STRUCTURE=$st; done
run --graph ppm --scene $hall --set PM_LIGHT_PATH_RATIO=4.5
run --graph pt --layout NaivePTsk --scene $hall
run --graph pt --layout StreamingPTmk2 --scene $hall
for s in $veach cornell-glossy-point "sponza --set PM_RADIUS=0.03"; do
  for w in true false; do run --graph ppm --scene $s --set PM_WHILE_QUERY=$w; run --graph pbpm --scene $s --set PM_WHILE_QUERY=$w; done
  for st in 1 3; do run --graph ppm --scene $s --set PM_STRUCTURE=$st; done
done
