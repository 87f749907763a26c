#!/usr/bin/env bash
# The chain estimators against VCM at a long budget (docs/performance.md, "Markov chains:
# adaptive photon tracing", the verify runs of 75 s and 240 s): one `lightgraph verify` of VCM
# and GRAPHS on SCENES. At 128x128 MMLT's 2048 chains were too few to decide in 240 s; at
# 256x256 (8192 chains) every chain estimator was decided. Blocks of 32 keep 64 blocks at
# 256x256, and 32 batches of several seconds (far longer than a chain's memory) lower the
# critical t. TIME is each estimator's, so a call takes about (1 + graphs) x TIME plus set-up:
# keep it under the device's 10 minutes. Bundle: --scene VeachAjar.
# Usage: [SCENES=...] [GRAPHS=mmlt] [RES=256x256] [TIME=240s] bash bench/mlt/verify.sh OUT_DIR
#   SCENES default: VeachAjar; e.g. SCENES=cornell-diffuse GRAPHS=mmlt,mvcm TIME=150s
set -euo pipefail
source "$(dirname "$0")/../common.sh"
OUT=${1:?OUT_DIR}
lg verify --scenes "${SCENES:-.gpu/scenes/VeachAjar/scene.xml}" --res "${RES:-256x256}" --block 32 \
  --batches 32 --time "${TIME:-240s}" --graphs "vcm,${GRAPHS:-mmlt}" --out "$OUT/verify"
