#!/usr/bin/env bash
# Photon mapping's rate targets on the GPU machine (docs/performance.md, "Photon mapping"),
# per kernel and repeated: after a warm-up, REPEATS interleaved rounds of 30 frames a run at
# 1280x720 on ModernHall of
# - PPMmkScreen (the density estimation a kernel of its own, in screen order: queries per
#   second of the gather) at the default radius and at r_0 = 0.0038 (about 20 photons a
#   query), and PPMmk (the same kernels, compacted: the queries out of screen order);
# - PPMsk and PPMmk's light pass (photon tracing), and PPMmk with PM_MEASURING (the light pass
#   without storing photons);
# - SPPM and PBPM (sk layouts) with NaiveQuery and WhileQuery (Table IV);
# - path tracing's extension rays: StreamingPTmk3 (trace, logic and material one kernel, as
#   PPMmk's light pass), WavefrontPT (trace alone), StreamingPTmk2 and NaivePTsk.
# The figure of a kernel is its minimum over the rounds (the H100's clocks swing up to 3x).
# Run from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene ModernHall`.
#   bash bench/gpu_pm_rates.sh LOG [REPEATS]
set -uo pipefail
log=${1:?usage: bash bench/gpu_pm_rates.sh LOG [REPEATS]}
repeats=${2:-3}
exec > >(tee "$log") 2>&1
lg() { bash .gpu/run.sh lightgraph "$@"; }
out=$(mktemp -d)
run() {
  echo "== $*"
  lg render --res 1280x720 --frames 30 --out "$out/x.exr" "$@" 2>&1 | grep -E "frames,|per frame|GPU time|rror"
}
lg render --graph pt --scene sponza --res 1280x720 --frames 200 --out "$out/warm.exr" >/dev/null 2>&1
hall=.gpu/scenes/ModernHall/staircase2.gltf
for round in $(seq "$repeats"); do
  echo "#### round $round"
  run --graph ppm --layout PPMmkScreen --scene $hall
  run --graph ppm --layout PPMmkScreen --scene $hall --set PM_RADIUS=0.0038
  run --graph ppm --layout PPMmk --scene $hall
  run --graph ppm --layout PPMmk --scene $hall --set PM_RADIUS=0.0038
  run --graph ppm --layout PPMsk --scene $hall
  run --graph ppm --layout PPMmk --scene $hall --set PM_MEASURING=true
  for g in sppm pbpm; do for w in false true; do run --graph $g --scene $hall --set PM_WHILE_QUERY=$w; done; done
  for l in StreamingPTmk3 WavefrontPT StreamingPTmk2 NaivePTsk; do run --graph pt --layout $l --scene $hall; done
done
echo "#### Sponza, once"
run --graph ppm --layout PPMmkScreen --scene sponza --set PM_RADIUS=0.03
run --graph ppm --layout PPMmk --scene sponza --set PM_RADIUS=0.03
for g in ppm pbpm; do for w in false true; do run --graph $g --scene cornell-glossy-point --set PM_WHILE_QUERY=$w; done; done
run --graph pt --layout StreamingPTmk3 --scene sponza
