#!/usr/bin/env bash
# PSSMLT on the GPU machine (docs/performance.md, "Markov chains: PSSMLT"): chain steps a
# second on Sponza against path tracing, acceptance on VeachAjar, and the study of PT, LVC-BPT,
# VCM and PSSMLT on VeachAjar. Bundle: --scene CrytekSponza --scene VeachAjar.
# Usage: bash bench/mlt/pssmlt.sh OUT_DIR
set -euo pipefail
source "$(dirname "$0")/../common.sh"
OUT=${1:?OUT_DIR}
S=.gpu/scenes/VeachAjar/scene.xml
lg bench --graph pssmlt --scene sponza --res 1280x720 --layouts all --time 2s --out "$OUT/bench-pssmlt"
lg bench --graph pt --scene sponza --res 1280x720 --layouts NaivePTsk --time 2s --out "$OUT/bench-pt"
lg render --graph pssmlt --scene $S --res 640x360 --time 10s --out "$OUT/ajar-pssmlt.exr"
lg render --graph pt --scene $S --res 640x360 --time 10s --out "$OUT/ajar-pt.exr"
lg study --scenes $S --res 640x360 --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,pssmlt:PSSMLTsk \
  --time 20s --reference-time 150s --out "$OUT/study-ajar"
