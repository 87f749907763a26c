#!/usr/bin/env bash
# Two binaries of the bundle against each other on the rates a shader change moves: PT on Sponza
# (NaivePTsk, StreamingPTmk2, 1280x720x16), LVC-BPTsk, VCMsk and VCMmk on Sponza and VCMsk on
# the 256x256 box (`vcm_rows`), NaiveBPT, NaiveBPTmk, StreamingBPT and LVC-BPTmk on Sponza
# (1280x720x1) and the diffuse box (512x512x4), and PPMsk's camera kernel at about 20 photons a query on five
# scenes (bench/pm/queries.sh, its higher radius of each), ROUNDS interleaved rounds
# (default 2). On the GPU machine from the repo root with carry [".gpu"] after
# `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza --scene ModernHall --scene
# VeachBidir` and the binary before copied to .gpu/bin/lightgraph-old:
#   bash bench/ab/rates.sh [OLD NEW]
# NO_BPT=1 leaves the BPT rows out (as in the Fresnel-term measurement, which had none).
set -uo pipefail
source "$(dirname "$0")/../common.sh"
old=${1:-lightgraph-old} new=${2:-lightgraph}
scenes=(
  "cornell-diffuse 0.0068"
  "cornell-glossy-point 0.0075"
  ".gpu/scenes/ModernHall/staircase2.gltf 0.0041"
  "sponza 0.052"
  ".gpu/scenes/VeachBidir/veach-bidir.gltf 0.008"
)
ppm_camera "$new" --scene cornell-glossy-point >/dev/null
for r in $(seq "${ROUNDS:-2}"); do
  for bin in "$old" "$new"; do
    bench_rows "$bin" "r$r $bin sponza" --time 2s --scene sponza --graph pt --layouts NaivePTsk,StreamingPTmk2 \
      --points 1280x720x16
    vcm_rows "$bin" "r$r $bin"
    [ -n "${NO_BPT:-}" ] || for point in sponza:1280x720x1 cornell-diffuse:512x512x4; do
      bench_rows "$bin" "r$r $bin ${point%%:*}" --time 2s --scene "${point%%:*}" --graph bpt-naive \
        --layouts NaiveBPT,NaiveBPTmk --points "${point#*:}"
      bench_rows "$bin" "r$r $bin ${point%%:*}" --time 2s --scene "${point%%:*}" --graph bpt-streaming \
        --layouts StreamingBPT --points "${point#*:}"
      bench_rows "$bin" "r$r $bin ${point%%:*}" --time 2s --scene "${point%%:*}" --graph bpt-lvc \
        --layouts LVC-BPTmk --points "${point#*:}"
    done
    for run in "${scenes[@]}"; do
      read -r scene radius <<<"$run"
      echo "r$r $bin PPMsk $(basename "$scene") r_0 $radius: $(ppm_camera "$bin" --scene "$scene" --set PM_RADIUS="$radius")"
    done
  done
done
