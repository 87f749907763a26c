#!/usr/bin/env bash
# The radix sort on the GPU machine (docs/performance.md, "Radix sort ranked by subgroup
# ballots"): 10^7 random keys, pairs and keys alone, 200 timed runs after the warm-up, three
# instances; the ballot ranking at 8 (default) and 4, 6, 10, 12 and 16 elements a thread; the
# portable ranking (--no-subgroups); the binary before (.gpu/bin/lightgraph-old, when bundled)
# as the baseline; then the kD-tree's build in PPM (Table V's column: Morton codes, sort,
# tree) with both binaries on ModernHall and cornell-glossy-point, 30 frames at 1280x720, two
# rounds. Run from the repo
# root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --bin BIN --scene ModernHall`
# (and `cp OLD .gpu/bin/lightgraph-old`):
#   bash bench/engine/sort.sh LOG
set -uo pipefail
log=${1:?usage: bash bench/engine/sort.sh LOG}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
ops() { bash .gpu/run.sh "$@" --sizes 10000000 --patterns random --keys random --runs 200; }
bins=(lightgraph)
[ -x .gpu/bin/lightgraph-old ] && bins+=(lightgraph-old)
echo "== ballots, 3 instances"
ops lightgraph operators --instances 3 --kernels
for items in 4 6 10 12 16; do echo "== ballots, $items a thread"; ops lightgraph operators --sort-items "$items" | grep -E '^\| 10000000 \| Random \| (pairs|keys)'; done
echo "== per-thread counts (--no-subgroups)"
ops lightgraph operators --no-subgroups | grep -E '^\| 10000000 \| Random \| (pairs|keys)'
if [ -x .gpu/bin/lightgraph-old ]; then echo "== before"; ops lightgraph-old operators --instances 3; fi
# The kD-tree's build a frame: the Morton codes, the sort's kernels and the tree.
kd_build() {
  bash .gpu/run.sh "$1" render --graph ppm --set PM_STRUCTURE=3 --res 1280x720 --frames 30 --out "$out/kd.exr" --force "${@:2}" 2>&1 |
    grep 'GPU time per frame' | tr ',' '\n' | grep -E 'kd_|lg_op' |
    awk '{ for (i = 1; i < NF; i++) if ($(i + 1) == "ms") { if ($(i - 1) ~ /lg_op/) sort += $i; total += $i } } END { printf "build %.3f ms a frame, of which the sort %.3f ms\n", total, sort }'
}
# Two rounds: the first binary's first render may still run at a low clock.
for round in 1 2; do
  for bin in "${bins[@]}"; do
    for scene in .gpu/scenes/ModernHall/staircase2.gltf cornell-glossy-point; do
      echo "== round $round, kD-tree, $bin, $scene: $(kd_build "$bin" --scene "$scene")"
    done
  done
done
