#!/usr/bin/env bash
# Large scenes (docs/performance.md, "Scenes of 10^6 to 10^8 triangles"; issue 43, item 2):
# Crytek Sponza placed on a grid of COPIES copies (default "1 4 40 400": 0.26, 1.05, 10.5 and
# 105 M triangles; `gltf_instances: [Grid(...)]`, 40 m apart along x and z), the camera of
# `sponza` in the first copy. For each size and BVH: the scene's load and BVH build (time,
# primitives/s, geometry bytes, from the render's header), then each of GRAPHS (default pt;
# each in its default layout) for SECONDS_EACH (default 5) and, unless TRACE=0, the trace-only
# rates (graphs/trace.ron, 20 frames). Above BIG copies (default 40) only the CWBVH and GRAPHS
# run: each load of such a scene
# takes minutes. Geometry larger than one storage binding is split over several buffers
# (scenes/src/split.rs); with SPLIT_AT=BYTES the sizes up to BIG also run split at that many
# bytes a binding (`--max-binding`), to measure what the split costs. A scene that does not fit
# the GPU's limits ends with the error naming them. On the GPU machine from the repo root with
# carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/traversal/large.sh                 COPIES="1 4" BVHS=cwbvh RES=64x36 for a quick look
set -uo pipefail
source "$(dirname "$0")/../common.sh"
out=$(mktemp -d)
grid() { # copies -> "nx, 1, nz" with nx * nz = copies, nx <= nz, as square as possible
  local n=$1 x
  x=$(awk -v n="$n" 'BEGIN { for (x = int(sqrt(n)); x > 1 && n % x; x--); print (x < 1 ? 1 : x) }')
  echo "$x, 1, $((n / x))"
}
for copies in ${COPIES:-1 4 40 400}; do
  scene=$out/sponza-$copies.ron
  sed -e "s|^    gltf: \"CrytekSponza/glTF/Sponza.gltf\",|    gltf: \"CrytekSponza/glTF/Sponza.gltf\",\n    gltf_instances: [Grid(counts: ($(grid "$copies")), spacing: (40.0, 0.0, 40.0))],|" \
    scenes/gltf/sponza.ron >"$scene"
  for bvh in ${BVHS:-cwbvh bvh2}; do
    big=$((copies > ${BIG:-40}))
    [ "$big" = 1 ] && [ "$bvh" != cwbvh ] && continue
    for split in "" ${SPLIT_AT:+--max-binding=$SPLIT_AT}; do
      [ "$big" = 1 ] && [ -n "$split" ] && continue
      echo "== $copies copies, $bvh $split"
      for graph in ${GRAPHS:-pt}; do
        lg render --graph "$graph" --scene "$scene" --bvh "$bvh" --res "${RES:-1280x720}" --time "${SECONDS_EACH:-5}s" \
          $split --out "$out/$graph.exr" --force 2>&1 | grep -E "primitives|frames,|rror" | sed 's/^.*| scene/scene/'
      done
      [ "$big" = 1 ] || [ "${TRACE:-1}" = 0 ] && continue
      lg render --graph trace --scene "$scene" --bvh "$bvh" --res "${RES:-1280x720}" --frames 20 \
        $split --out "$out/trace.exr" --force >"$out/trace.log" 2>&1 || grep -m1 rror "$out/trace.log"
      grep -E "^per frame|^GPU time per frame" "$out/trace.log"
    done
  done
done
