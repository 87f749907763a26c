#!/usr/bin/env bash
# The engine's collective operators and shared memory on the GPU machine (docs/performance.md,
# "Engine: collective operators and shared memory"); run from the repo root with carry [".gpu"]
# after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`.
#   bash bench/engine/operators.sh
set -uo pipefail
lg() { bash .gpu/run.sh lightgraph "$@" 2>&1 | grep -v "^NVIDIA"; }
echo "== exclusive scan of 10^7 u32 and counting sort of 10^7 keys into 10^7 buckets (12-byte elements)"
lg operators --sizes 10000000 --runs 50 --patterns random,equal --kernels | grep -v "^subgroup\|^adapter"
echo "== the same without subgroup operations"
lg operators --sizes 10000000 --runs 50 --patterns random --no-subgroups --kernels | grep -v "^adapter"
echo "== against the CPU at every boundary and at 10^8"
lg operators --sizes 0,1,2,31,32,33,255,256,257,4095,4096,4097,1048583,100000000 --runs 3 | grep -v "^subgroup\|^adapter"
echo "== LVC-BPT memory on Sponza, 1280x720, 1 sample per pixel"
for layout in LVC-BPTsk LVC-BPTmk; do
  lg explain --graph bpt-lvc --layout $layout --scene sponza --res 1280x720 --spp 1 | grep -E "^layout|^measured|GPU memory"
done
echo "== LVC-BPT and PT rates (cornell-glossy-point 512x512, 4 spp; cornell-mitsuba 1280x720)"
for layout in LVC-BPTsk LVC-BPTmk; do
  lg render --graph bpt-lvc --layout $layout --scene cornell-glossy-point --res 512x512 --spp 4 --time 6s --out /tmp/lvc.exr | grep -E "samples/s"
done
rm -rf /tmp/bench # bench refuses a folder holding an earlier bench
lg bench --scene cornell-mitsuba --graph pt --layouts NaivePTsk,StreamingPTmk1,StreamingPTmk2 --points 1280x720x1 --time 1s --out /tmp/bench | grep "^| [NS]"
