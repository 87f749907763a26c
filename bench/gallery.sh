#!/usr/bin/env bash
# The gallery of docs/gallery/: every scene file of scenes/cornell, scenes/gltf, scenes/media and scenes/study, every
# glTF asset of the shared scenes given bare on the command line (default camera, default
# environment when it has no light), and every Mitsuba scene file (scene.xml) of the shared
# scenes, rendered with PT on the GPU machine from the repo root
# with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene NAME ...` for the assets.
# PNG previews land in OUT_DIR; a failing scene is reported and the sweep goes on.
#   bash bench/gallery.sh OUT_DIR [SECONDS]
set -uo pipefail
out=${1:?usage: bash bench/gallery.sh OUT_DIR [SECONDS]}
secs=${2:-4}
lg() { bash .gpu/run.sh lightgraph "$@"; }
mkdir -p "$out"
work=$(mktemp -d)
shot() {
  local name=$1; shift
  local extra=()
  case $name in sponza) extra=(--exposure 2) ;; esac
  if lg render "$@" "${extra[@]}" --res 480x270 --spp 4 --time "${secs}s" --out "$work/$name.exr" >"$work/$name.log" 2>&1; then
    cp "$work/$name.png" "$out/$name.png"
    echo "ok   $name: $(grep ' spp in ' "$work/$name.log" | cut -d: -f1)"
  else
    echo "FAIL $name: $(tail -2 "$work/$name.log" | tr '\n' ' ')"
  fi
}
for f in scenes/cornell/*.ron scenes/gltf/*.ron scenes/media/*.ron scenes/study/*.ron; do
  [ -e "$out/$(basename "$f" .ron).png" ] && continue
  shot "$(basename "$f" .ron)" --scene "$(basename "$f" .ron)"
done
for f in $(find .gpu/scenes -name '*.gltf' -o -name '*.glb' | sort); do
  name=$(basename "$f"); name=${name%.*}
  [ -e "$out/$name.png" ] || shot "$name" --scene "$f"
done
# Mitsuba scene files (Bitterli's originals beside their glTF conversions), named after their
# folder: VeachBidir-xml.png.
for f in $(find .gpu/scenes -name 'scene.xml' | sort); do
  name=$(basename "$(dirname "$f")")-xml
  [ -e "$out/$name.png" ] || shot "$name" --scene "$f"
done
