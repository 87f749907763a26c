#!/usr/bin/env bash
# Metropolised VCM on the GPU machine (docs/performance.md, "Markov chains: Metropolised VCM"),
# in three device calls.
#   bash bench/mlt/mvcm.sh rates OUT_DIR    chain steps a second on Sponza (bundle: --scene
#                                           CrytekSponza --scene VeachAjar), the verify of the
#                                           boxes and of VeachAjar at 128x128 with 8 s an
#                                           estimator, acceptance on VeachAjar
#   bash bench/mlt/mvcm.sh ajar OUT_DIR [REFS]    the study on VeachAjar (PT, LVC-BPT, VCM,
#                                           PSSMLT, Metropolised LVC-BPT and VCM) against a VCM
#                                           reference of 200 s (rendered, or taken from REFS)
#   bash bench/mlt/mvcm.sh caustics OUT_DIR [REFS]  the same on LivingRoom's reflected caustic
#                                           (bundle: --scene VeachAjar --scene LivingRoom)
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
  lg study --scenes $AJAR --res 640x360 \
    --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,pssmlt:PSSMLTsk,mvcm:MVCMsk,mvcm:MVCMsk@VCM_MERGE=false \
    --time 20s --reference-time 200s ${3:+--references "$3"} --out "$OUT/study-ajar"
  ;;
caustics)
  lg study --scenes $CAUSTICS --res 640x360 \
    --estimators pt:NaivePTsk,bpt-lvc:LVC-BPTsk,vcm:VCMsk,pssmlt:PSSMLTsk,mvcm:MVCMsk \
    --time 20s --reference-time 200s ${3:+--references "$3"} --out "$OUT/study-caustics"
  ;;
esac
