#!/bin/bash
# lightgraph's path tracer against Cycles (cycles_reference.py) on glTF sample models: one
# Markdown table row per model (docs/gltf.md). Usage:
#   PYTHON_BPY=V/bin/python LIGHTGRAPH=target/release/lightgraph bench/peers/gltf/compare.sh OUT_DIR [MODEL.gltf ...]
# Defaults: the models of docs/gltf.md under ../shared/scenes; RES=64x64; lightgraph FRAMES=16
# of SPP=16 (NaivePTsk); Cycles PASSES=8 of CYCLES_SPP=32; BLOCK=8. The comparison needs
# numpy and mitsuba (bench/peers/mitsuba_scenes.py reads the EXR with it).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: compare.sh OUT_DIR [MODEL.gltf ...]}
shift
scenes=${SCENES:-$here/../../../../shared/scenes}
models=("$@")
if [ ${#models[@]} -eq 0 ]; then
  for m in Box Duck DamagedHelmet MetalRoughSpheresNoTextures TransmissionTest EmissiveStrengthTest; do
    models+=("$scenes/$m/glTF/$m.gltf")
  done
fi
res=${RES:-64x64}
mkdir -p "$out"
echo "| model | Cycles mean | lightgraph - Cycles | z (mean) | blocks | beyond | worst block z (rel.) | critical |"
echo "|---|---|---|---|---|---|---|---|"
for model in "${models[@]}"; do
  name=$(basename "$model" .gltf)
  "${PYTHON_BPY:-python3}" "$here/cycles_reference.py" render "$model" "$out/$name.npz" --res "$res" \
    --spp "${CYCLES_SPP:-32}" --batches "${PASSES:-8}" > "$out/$name-cycles.log" 2>&1
  "${LIGHTGRAPH:-lightgraph}" render --scene "$model" --graph pt --layout NaivePTsk --res "$res" \
    --spp "${SPP:-16}" --frames "${FRAMES:-16}" --seed 7 --out "$out/$name.exr" > "$out/$name-lightgraph.log" 2>&1
  python3 "$here/../mitsuba_scenes.py" compare "$out/$name.exr" "$out/$name.npz" --block "${BLOCK:-8}" --name "$name"
done
