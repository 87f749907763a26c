#!/usr/bin/env bash
# Adaptive Markov chain photon tracing on the GPU machine (docs/performance.md, "Markov chains:
# adaptive photon tracing"), in one call of under 10 minutes: visibility and acceptance on
# VeachAjar, the study of PT, LVC-BPT, VCM, PPM and adaptive PPM there, photon paths a second
# on Sponza against PPM, verify against PPM and VCM, a chain's iterations a frame, and PSSMLT
# against PT at a long budget (its start-up bias). Bundle: --scene CrytekSponza --scene VeachAjar.
# Usage: bash bench/mlt/appm.sh OUT_DIR
set -euo pipefail
source "$(dirname "$0")/../common.sh"
OUT=${1:?OUT_DIR}
S=.gpu/scenes/VeachAjar/scene.xml
lg render --graph appm --scene $S --res 640x360 --time 10s --out "$OUT/ajar-appm.exr"
lg render --graph ppm --scene $S --res 640x360 --time 10s --out "$OUT/ajar-ppm.exr"
lg study --scenes $S --res 640x360 --time 15s --reference-time 150s \
  --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,ppm:PPMsk,appm:APPMsk --out "$OUT/study-ajar"
lg bench --graph appm --scene sponza --res 1280x720 --layouts all --time 2s --out "$OUT/bench-appm"
lg bench --graph ppm --scene sponza --res 1280x720 --layouts PPMsk --time 2s --out "$OUT/bench-ppm"
lg verify --scenes cornell-glossy-point,$S --res 128x128 --time 6s --graphs ppm,appm,vcm --out "$OUT/verify-appm" || true
for k in 1 2 4; do
  lg render --graph appm --scene $S --res 640x360 --time 4s --set AMC_CHAIN_STEPS=$k --out "$OUT/ajar-appm-$k.exr"
done
lg verify --scenes cornell-diffuse,$S --res 128x128 --time 12s --graphs pt,pssmlt --out "$OUT/verify-pssmlt" || true
