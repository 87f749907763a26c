#!/usr/bin/env bash
# Photon mapping's rate targets on the GPU machine (docs/performance.md, "Photon mapping"),
# per kernel and repeated: after a warm-up of 10 s, REPEATS interleaved rounds of 30 frames a
# run at 1280x720 on ModernHall of
# - PPMmkScreen (the density estimation a kernel of its own, queries in screen order, 8x8
#   pixel tiles) and PPMsk (one camera kernel), at the default radius and at r_0 = 0.0038
#   (about 20 photons a query), PPMsk with PM_MEASURING (no photon stored: the camera kernel
#   without the photon loops) and PPMmk (compacted: queries out of screen order);
# - photon tracing (PPMsk and PPMmk's light passes) against path tracing's extension rays:
#   StreamingPTmk3 (trace, logic and material one kernel, as PPMmk's light pass),
#   StreamingPTmk2 and NaivePTsk;
# - SPPM and PBPM (sk layouts) with NaiveQuery and WhileQuery (Table IV).
# The figure of a kernel is its minimum over the rounds (the H100's clocks swing up to 3x).
# Run from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene ModernHall`.
#   bash bench/pm/rates.sh LOG [REPEATS]
set -uo pipefail
log=${1:?usage: bash bench/pm/rates.sh LOG [REPEATS]}
repeats=${2:-3}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
run() { render_summary 30 "$@"; }
lg render --graph pt --scene sponza --res 1280x720 --time 10s --out "$out/warm.exr" >/dev/null 2>&1
hall=.gpu/scenes/ModernHall/staircase2.gltf
for round in $(seq "$repeats"); do
  echo "#### round $round"
  for r in 0.003 0.0038; do
    run --graph ppm --layout PPMmkScreen --scene $hall --set PM_RADIUS=$r
    run --graph ppm --layout PPMsk --scene $hall --set PM_RADIUS=$r
  done
  run --graph ppm --layout PPMsk --scene $hall --set PM_MEASURING=true
  run --graph ppm --layout PPMmk --scene $hall
  for l in StreamingPTmk3 StreamingPTmk2 NaivePTsk; do run --graph pt --layout $l --scene $hall; done
  for g in sppm pbpm; do for w in false true; do run --graph $g --scene $hall --set PM_WHILE_QUERY=$w; done; done
done
echo "#### Sponza and the glossy box, once"
run --graph ppm --layout PPMmk --scene sponza --set PM_RADIUS=0.03
run --graph pt --layout StreamingPTmk3 --scene sponza
for g in ppm pbpm; do for w in false true; do run --graph $g --scene cornell-glossy-point --set PM_WHILE_QUERY=$w; done; done
