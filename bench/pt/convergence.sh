#!/usr/bin/env bash
# Error-against-time and stress measurements of docs/performance.md, run on the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
# the stress suite at scale 8 (and the enclosure and glass cases at 8192 and 4096 samples per
# pixel); a bench point per scene; a reference and a compare of PT layouts on the Mitsuba
# Cornell box and on Crytek Sponza. Everything but the console output is packed into OUT_DIR/results.tgz.
#   bash bench/pt/convergence.sh OUT_DIR
set -uo pipefail
out=${1:?usage: bash bench/pt/convergence.sh OUT_DIR}
lg() { bash .gpu/run.sh lightgraph "$@"; }
work=$(mktemp -d)
start=$(date +%s)
step() { echo "== $* ($(( $(date +%s) - start )) s)"; }
step stress
lg stress --scale 8 --spp 16 --frames 64 --out "$work/stress" 2>&1 | grep -v "^|" | tail -22
lg stress --only inside --scale 8 --spp 64 --frames 128 --out "$work/stress-inside" 2>&1 | grep "^  " -A1
lg stress --only glass --scale 8 --spp 64 --frames 64 --out "$work/stress-glass" 2>&1 | grep "^  " -A1
rm -f "$work"/stress*/*.png
step bench
lg bench --scene cornell-mitsuba --layouts NaivePTsk,StreamingPTmk1 --points 1280x720x16 --time 2s --out "$work/bench-cornell" 2>&1 | grep "paths"
lg bench --scene sponza --layouts NaivePTsk,StreamingPTmk2 --points 1280x720x16 --time 2s --out "$work/bench-sponza" 2>&1 | grep "paths"
step cornell reference
lg reference --scene cornell-mitsuba --spp 16 --time 40s --out "$work/cornell/ref.exr" 2>&1 | tail -1
step cornell compare
lg compare --scene cornell-mitsuba --spp 16 --reference "$work/cornell/ref.exr" --time 8s \
  --runs pt:NaivePTsk,pt:RegenerationPTsk,pt:StreamingPTmk1,pt:NaivePTmk --out "$work/cornell/compare" 2>&1 | grep "^|"
step sponza reference
lg reference --scene sponza --spp 4 --time 60s --out "$work/sponza/ref.exr" 2>&1 | tail -1
step sponza compare
lg compare --scene sponza --spp 4 --reference "$work/sponza/ref.exr" --time 10s \
  --runs pt:NaivePTsk,pt:RegenerationPTsk,pt:StreamingPTmk2 --out "$work/sponza/compare" 2>&1 | grep "^|"
rm -f "$work"/*/ref.exr "$work"/*/compare/*.exr
step done
tar czf "$out/results.tgz" -C "$work" .
