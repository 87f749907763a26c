#!/usr/bin/env bash
# What scene-specialised kernels buy (docs/performance.md, "Scene-specialised kernels"): PT's
# best layouts on the Mitsuba Cornell box and on Crytek Sponza, 1280x720 at 16 samples per
# pixel per frame, with the kernels specialised for the scene and with every feature compiled
# in (--all-features); run on the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --scene CrytekSponza --scene envmaps`.
#   bash bench/engine/specialise.sh OUT_DIR
set -uo pipefail
out=${1:?usage: bash bench/engine/specialise.sh OUT_DIR}
lg() { bash .gpu/run.sh lightgraph "$@"; }
for scene in cornell-mitsuba:NaivePTsk,StreamingPTmk1 sponza:NaivePTsk,StreamingPTmk2 sponza-many-lights:NaivePTsk,StreamingPTmk2; do
  name=${scene%%:*} layouts=${scene#*:}
  for mode in specialised all; do
    flag=; [ $mode = all ] && flag=--all-features
    echo "== $name $mode"
    lg explain --scene "$name" --layout "${layouts%%,*}" $flag 2>/dev/null | grep -E "WGSL lines|left out"
    lg bench --scene "$name" --layouts "$layouts" --points 1280x720x16 --time 3s $flag \
      --out "$out/bench-$name-$mode" 2>&1 | grep -E "^\|" 
  done
done
