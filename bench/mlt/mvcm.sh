#!/usr/bin/env bash
# Metropolised VCM on the GPU machine (docs/performance.md, "Markov chains: Metropolised VCM"),
# in three device calls.
#   bash bench/mlt/mvcm.sh rates OUT_DIR    chain steps a second on Sponza (bundle: --scene
#                                           CrytekSponza --scene VeachAjar), the verify of the
#                                           boxes and of VeachAjar at 128x128 with 8 s an
#                                           estimator, acceptance on VeachAjar
#   bash bench/mlt/mvcm.sh ajar OUT_DIR [REFS]    rates by MLT_CHAIN_STEPS and the study on
#                                           VeachAjar (PT, LVC-BPT, VCM, PSSMLT, Metropolised
#                                           LVC-BPT and VCM, the latter also with a chain a
#                                           sample) against a VCM reference of 200 s
#                                           (rendered, or taken from REFS)
#   bash bench/mlt/mvcm.sh caustics OUT_DIR [REFS]  PT, VCM, PSSMLT and Metropolised VCM on
#                                           LivingRoom's reflected caustic, 15 s each against a
#                                           VCM reference of 120 s (bundle: --scene VeachAjar
#                                           --scene LivingRoom)
set -euo pipefail
source "$(dirname "$0")/../common.sh"
OUT=${2:?OUT_DIR}
AJAR=.gpu/scenes/VeachAjar/scene.xml
CAUSTICS=.gpu/scenes/LivingRoom/living-room-caustics.gltf
case ${1:?rates, ajar or caustics} in
rates)
  lg bench --graph mvcm --scene sponza --res 1280x720 --layouts all --time 2s --out "$OUT/bench-mvcm"
  lg render --graph mvcm --scene $AJAR --res 640x360 --time 10s --out "$OUT/ajar-mvcm.exr"
  lg verify --scenes cornell-diffuse,cornell-glossy-point,$AJAR --res 128x128 --time 8s \
    --graphs vcm,mvcm,mvcm@MLT_INDEPENDENT=true,vcm@VCM_MERGE=false,mvcm@VCM_MERGE=false --out "$OUT/verify" || true
  ;;
ajar)
  for steps in 8 2 1; do
    lg render --graph mvcm --scene $AJAR --res 640x360 --time 5s --set MLT_CHAIN_STEPS=$steps --out "$OUT/ajar-steps$steps.exr"
  done
  lg study --scenes $AJAR --res 640x360 \
    --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,pssmlt:PSSMLTsk,mvcm:MVCMsk,mvcm:MVCMsk@MLT_CHAIN_STEPS=1,mvcm:MVCMsk@VCM_MERGE=false \
    --time 20s --reference-time 200s ${3:+--references "$3"} --out "$OUT/study-ajar"
  ;;
caustics)
  lg study --scenes $CAUSTICS --res 640x360 \
    --estimators pt:NaivePTsk,vcm:VCMsk,pssmlt:PSSMLTsk,mvcm:MVCMsk \
    --time 15s --reference-time 120s ${3:+--references "$3"} --out "$OUT/study-caustics"
  ;;
esac
