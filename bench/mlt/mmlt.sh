#!/usr/bin/env bash
# MMLT on the GPU machine (docs/performance.md, "Markov chains: MMLT"), in two device calls.
# Bundle: --scene CrytekSponza --scene VeachAjar.
#   bash bench/mlt/mmlt.sh rates OUT_DIR   chain steps a second on Sponza, the verify of the boxes
#                                          at 128x128 with 8 s an estimator
#   bash bench/mlt/mmlt.sh study OUT_DIR [REFS]  acceptance on VeachAjar, its verify at 128x128,
#                                          and its study (PT, LVC-BPT, VCM, PSSMLT, MMLT) against
#                                          a VCM reference of 200 s (rendered, or taken from REFS)
set -euo pipefail
source "$(dirname "$0")/../common.sh"
OUT=${2:?OUT_DIR}
S=.gpu/scenes/VeachAjar/scene.xml
case ${1:?rates or study} in
rates)
  lg bench --graph mmlt --scene sponza --res 1280x720 --layouts all --time 2s --out "$OUT/bench-mmlt"
  lg verify --scenes cornell-diffuse,cornell-glossy-point --res 128x128 --time 8s \
    --graphs pt,bpt-naive,vcm,pssmlt,mmlt,mmlt@MLT_INDEPENDENT=true --out "$OUT/verify" || true
  ;;
study)
  lg render --graph mmlt --scene $S --res 640x360 --time 10s --out "$OUT/ajar-mmlt.exr"
  lg verify --scenes $S --res 128x128 --time 8s --graphs pt,bpt-naive,pssmlt,mmlt --out "$OUT/verify-ajar" || true
  lg study --scenes $S --res 640x360 --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,pssmlt:PSSMLTsk,mmlt:MMLTsk \
    --time 20s --reference-time 200s ${3:+--references "$3"} --out "$OUT/study-ajar"
  ;;
esac
