#!/usr/bin/env bash
# Two batches in flight, statistics read back one batch behind (issue 16, item 1;
# docs/performance.md, "Batches in flight"). On the GPU machine from the repo root with carry
# [".gpu"] after `../shared/tools/gpu-bundle.sh --bin NEW --scene CrytekSponza` and the binary
# before the change copied to .gpu/bin/lightgraph-old:
#   bash bench/engine/inflight.sh OUT_DIR
# Rates at about 10^6 paths a frame (1280x720x1), where a frame takes a millisecond or two and
# the gap between batches shows most, for PT's megakernels and pooled layouts on the Cornell
# box and Sponza, and VCM's iterations at 256x256 (SmallVCM's setting), 1.5 s a point, in two
# rounds of old then new (the H100's clocks drift between runs of one call); then PT's paths
# in 8x8 pixel tiles against rows (--set TILED_PIXELS). Writes OUT_DIR/inflight.md.
set -uo pipefail
out=${1:?usage: bash bench/engine/inflight.sh OUT_DIR}
mkdir -p "$out"
log=$out/inflight.md
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1 | tee "$log"
bench() { # $1 = binary, $2 = title, then bench arguments; appends the rate table
  local bin=$1 title=$2
  shift 2
  echo "### $title ($bin)" >>"$log"
  rm -rf /tmp/gpu-inflight # bench refuses a folder holding an earlier bench
  bash .gpu/run.sh "$bin" bench "$@" --out /tmp/gpu-inflight >/dev/null 2>/tmp/gpu-inflight.err ||
    tail -3 /tmp/gpu-inflight.err | tee -a "$log"
  sed -n '/^| layout | [0-9]/,/^$/p' /tmp/gpu-inflight/bench.md >>"$log"
}
pt_layouts=NaivePTsk,NaivePTmk,StreamingPTmk1,StreamingPTmk2,WavefrontPT
for round in 1 2; do
  for bin in lightgraph-old lightgraph; do
    for s in cornell-mitsuba sponza; do
      bench $bin "pt $s round $round" --scene $s --graph pt --layouts $pt_layouts --time 1.5s --points 1280x720x1
    done
    bench $bin "vcm round $round" --scene cornell-diffuse --graph vcm --layouts VCMsk,VCMmk --time 1.5s --points 256x256x1
  done
  # PT's camera paths in 8x8 pixel tiles (TILED_PIXELS) against rows, the new binary.
  for tiled in false true; do
    bench lightgraph "pt sponza tiled=$tiled round $round" --scene sponza --graph pt \
      --layouts NaivePTsk,StreamingPTmk1,StreamingPTmk2 --time 1.5s --points 1280x720x1,1280x720x16 --set TILED_PIXELS=$tiled
    bench lightgraph "pt cornell tiled=$tiled round $round" --scene cornell-mitsuba --graph pt \
      --layouts NaivePTsk,StreamingPTmk1 --time 1.5s --points 1280x720x16 --set TILED_PIXELS=$tiled
  done
done
cat "$log"
