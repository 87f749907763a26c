#!/usr/bin/env bash
# The paper's Table VI (docs/performance.md, "Photon mapping"): PPM with each structure (full
# hash grid, rectified stochastic hash grid, kD-tree) for the same wall-clock time, and each
# one's time to the error the baseline (full grid) ends at, against a path-traced reference
# (PT reaches every path on these scenes): the glossy Cornell box with a point light at
# 512x512, ModernHall, VeachBidir, LivingRoom (white background for its sky) and Sponza
# (r_0 = 0.03: the default finds almost no photon there) at 640x360. Run from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene ModernHall --scene
# VeachBidir --scene LivingRoom --scene CrytekSponza` (or fewer, with TABLES naming the
# tables to make: any of cornell-glossy-point modern-hall veach-bidir living-room sponza).
#   bash bench/pm/table6.sh LOG [SECONDS] [REFERENCE_SECONDS]
set -uo pipefail
log=${1:?usage: bash bench/pm/table6.sh LOG [SECONDS] [REFERENCE_SECONDS]}
secs=${2:-20}
ref_secs=${3:-90}
exec > >(tee "$log") 2>&1
out=${OUT:-$(mktemp -d)}
source "$(dirname "$0")/../common.sh"
tables=${TABLES:-cornell-glossy-point modern-hall veach-bidir living-room sponza}
table6() { # NAME SCENE RES [@NAME=VALUE, a setting of every run]
  local name=$1 scene=$2 res=$3 set=${4:-}
  [[ " $tables " == *" $name "* ]] || return 0
  local runs=ppm:PPMsk@PM_STRUCTURE=0$set,ppm:PPMsk@PM_STRUCTURE=1$set,ppm:PPMsk@PM_STRUCTURE=3$set
  echo "== $name"
  lg reference --graph pt --layout StreamingPTmk2 --scene "$scene" --res "$res" --time "${ref_secs}s" \
    --out "$out/$name-ref.exr" 2>&1 | tail -2
  lg compare --scene "$scene" --runs $runs --reference "$out/$name-ref.exr" --time "${secs}s" \
    --out "$out/$name" 2>&1 | tail -3
  cat "$out/$name/summary.md"
}
table6 cornell-glossy-point cornell-glossy-point 512x512
table6 modern-hall .gpu/scenes/ModernHall/staircase2.gltf 640x360
table6 veach-bidir .gpu/scenes/VeachBidir/veach-bidir.gltf 640x360
table6 living-room .gpu/scenes/LivingRoom/living-room.gltf 640x360
table6 sponza sponza 640x360 @PM_RADIUS=0.03
