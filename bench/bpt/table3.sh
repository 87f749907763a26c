#!/usr/bin/env bash
# Error against time of the bidirectional estimators (docs/performance.md, "Bidirectional
# path tracing", Table III): a long LVC-BPT reference (5 x SECONDS), then `lightgraph compare`
# of StreamingBPT (the baseline, as in the paper's Table III), NaiveBPT, LVC-BPTsk, LVC-BPTmk
# and PT, SECONDS each, on the glossy Cornell box with a point light (cornell-glossy-point) and
# on Crytek Sponza, and `explain`'s memory of each BPT graph; run on the GPU machine from the
# repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza
# --scene envmaps`. Results are packed into OUT_DIR/bpt.tgz.
#   bash bench/bpt/table3.sh OUT_DIR [SECONDS]
# AT_ONCE=N makes StreamingBPT rendering N frames at once (`@FRAMES_AT_ONCE=N`) the baseline,
# StreamingBPT one frame at a time a run beside it ("Again with StreamingBPT rendering 16
# frames at once": `AT_ONCE=16 bash bench/bpt/table3.sh OUT_DIR 8`).
set -uo pipefail
out=${1:?usage: [AT_ONCE=N] bash bench/bpt/table3.sh OUT_DIR [SECONDS]}
secs=${2:-8}
lg() { bash .gpu/run.sh lightgraph "$@"; }
baseline=bpt-streaming:StreamingBPT
runs=bpt-streaming:StreamingBPT,bpt-naive:NaiveBPT,bpt-lvc:LVC-BPTsk,bpt-lvc:LVC-BPTmk,pt:StreamingPTmk2
if [ -n "${AT_ONCE:-}" ]; then
  baseline=bpt-streaming:StreamingBPT@FRAMES_AT_ONCE=$AT_ONCE
  runs=$baseline,$runs
fi
work=$(mktemp -d)
for scene in cornell-glossy-point:512x512:4 sponza:1280x720:1; do
  IFS=: read -r name res spp <<<"$scene"
  echo "== $name reference"
  lg reference --graph bpt-lvc --layout LVC-BPTmk --scene "$name" --res "$res" --spp "$spp" --time "$((secs * 5))s" \
    --out "$work/$name/ref.exr" 2>&1 | tail -1
  echo "== $name compare"
  lg compare --scene "$name" --res "$res" --spp "$spp" --reference "$work/$name/ref.exr" --time "${secs}s" \
    --baseline "$baseline" --runs "$runs" --out "$work/$name/compare" 2>&1 | grep -E "^\||overflow"
  for g in bpt-streaming bpt-naive bpt-lvc; do
    lg explain --graph $g --scene "$name" --res "$res" --spp "$spp" 2>/dev/null | grep -E "^layout|GPU memory|queue|state of|lvc_cache|lvc_staging"
  done
done
rm -f "$work"/*/ref.exr "$work"/*/compare/*.exr
tar czf "$out/bpt.tgz" -C "$work" .
