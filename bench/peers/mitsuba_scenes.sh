#!/usr/bin/env bash
# Issue 39's acceptance on the GPU machine: lightgraph's path tracer against Mitsuba 3's own
# renders of Mitsuba scene files (bench/peers/mitsuba_scenes.py), and what smooth shading costs.
# Run HERE first:
#
#   bash bench/peers/prepare_wheels.sh
#   cargo build --release && ../shared/tools/gpu-bundle.sh --scene VeachBidir --scene ModernHall \
#       --scene VeachAjar && strip .gpu/bin/lightgraph && bash bench/peers/pack.sh
#
# then on the GPU machine, carry [".peers.tar.xz"]:
#
#   bash bench/peers/mitsuba_scenes.sh all $OUT   # compare, cost and verify in one call
#
# compare: Mitsuba (cuda_ad_rgb) and lightgraph renders of each scene; cost: ModernHall with
# vertex normals and without; verify: PT, LVC-BPT and VCM on the smooth-normal scenes. The
# results go to $OUT: per scene NAME.tar (NAME-mitsuba.npz, NAME-lightgraph.exr and the logs)
# and logs.tar (verify's tables, the cost runs' logs); compare here with `python3 bench/peers/mitsuba_scenes.py compare
# NAME-lightgraph.exr NAME-mitsuba.npz --name NAME`. Environment: SECONDS_LG (lightgraph's time
# per scene, default 15), SPP (Mitsuba's samples per batch, default 512), BATCHES (default 8).
set -uo pipefail
mode=${1:?usage: mitsuba_scenes.sh compare|cost OUT}
out=${2:?usage: mitsuba_scenes.sh compare|cost OUT}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root" || exit 1
mkdir -p "$out"
work=/tmp/mitsuba-scenes
mkdir -p "$work"
if [ -f .peers.tar.xz ] && [ ! -d .peers-site ]; then
  tar -xJf .peers.tar.xz || { echo "cannot unpack .peers.tar.xz" >&2; exit 1; }
fi
export PYTHONPATH=$root/.peers-site${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
lib=$(ldconfig -p 2>/dev/null | awk '$1 ~ /^libcuda[.]so[.]1$/ { print $NF; exit }')
[ -n "$lib" ] && [ -z "$(ldconfig -p | awk '$1 ~ /^libcuda[.]so$/')" ] && export DRJIT_LIBCUDA_PATH=$lib
lg() { bash .gpu/run.sh lightgraph "$@"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$work/device.txt"

# name, scene file, resolution
scenes=(
  "smooth-spheres bench/peers/scenes/smooth-spheres/scene.xml 256x256"
  "veach-bidir .gpu/scenes/VeachBidir/scene.xml 256x256"
  "modern-hall .gpu/scenes/ModernHall/scene.xml 320x180"
  "veach-ajar .gpu/scenes/VeachAjar/scene.xml 320x180"
)

compare() {
  for entry in "${scenes[@]}"; do
    read -r name file res <<< "$entry"
    echo "=== $name ($res)"
    local t0=$SECONDS
    python3 bench/peers/mitsuba_scenes.py render "$file" "$work/$name-mitsuba.npz" --res "$res" \
      --spp "${SPP:-512}" --batches "${BATCHES:-8}" --variant cuda_ad_rgb > "$work/$name-mitsuba.log" 2>&1 \
      || tail -5 "$work/$name-mitsuba.log"
    echo "mitsuba: $((SECONDS - t0)) s"
    lg render --scene "$file" --res "$res" --spp 4 --time "${SECONDS_LG:-15}s" \
      --out "$work/$name-lightgraph.exr" > "$work/$name-lightgraph.log" 2>&1 || tail -5 "$work/$name-lightgraph.log"
    grep -h "warning" "$work/$name-lightgraph.log" | sort | uniq -c | head -20
    grep -h "samples/s" "$work/$name-lightgraph.log"
  done
}

# ModernHall as it is (vertex normals) and with face_normals on every mesh: what smooth
# shading costs path tracing, the same geometry either way.
cost() {
  local flat=.gpu/scenes/ModernHall/scene-flat.xml
  sed -E 's|<shape type="obj" *>|<shape type="obj"><boolean name="face_normals" value="true"/>|' \
    .gpu/scenes/ModernHall/scene.xml > "$flat"
  for variant in scene scene-flat; do
    for layout in NaivePTsk WavefrontPT; do
      echo "=== ModernHall $variant $layout"
      lg render --scene ".gpu/scenes/ModernHall/$variant.xml" --res 1280x720 --layout "$layout" \
        --spp 4 --time 10s --out "$work/cost-$variant-$layout.exr" > "$work/cost-$variant-$layout.log" 2>&1
      grep -h "samples/s" "$work/cost-$variant-$layout.log"
    done
  done
}

# PT, LVC-BPT and VCM on the scenes with smooth normals (the verify of issue 39).
verify() {
  lg verify --scenes bench/peers/scenes/smooth-spheres/scene.xml,.gpu/scenes/VeachBidir/scene.xml \
    --graphs pt,bpt-lvc,vcm --res 256x256 --time 6s --out "$work/verify" > "$work/verify.log" 2>&1
  tail -3 "$work/verify.log"
  cat "$work/verify/verify.md" 2>/dev/null | head -40
}

all() {
  compare
  verify
  cost
}

"$mode"
# What comes back: at most 8 files of 16 MiB.
for entry in "${scenes[@]}"; do
  read -r name _ <<< "$entry"
  (cd "$work" && ls "$name"-* >/dev/null 2>&1 && tar -cf "$out/$name.tar" "$name"-*)
done
(cd "$work" && tar -cf "$out/logs.tar" device.txt ./*.log verify/verify.md verify/verify.csv 2>/dev/null)
ls -la "$out"
