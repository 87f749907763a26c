#!/usr/bin/env bash
# Scale-out on one machine (docs/performance.md, "Scale-out"): PT (StreamingPTmk2) and LVC-BPT
# (LVC-BPTsk) on Sponza at 1280x720 for SECONDS each, on one GPU in one process, on every GPU
# in one process (--gpus all) and with one MPI rank per GPU (--mpi), after a warm-up of every
# GPU; the summary lines give samples/s, frames per GPU or rank, the host's merge time per
# batch and the time of the last film reduction. Run on a multi-GPU kind from the repo root
# with carry [".gpu"], a binary built with --features mpi, and Open MPI's Debian packages in
# .gpu/debs (run.sh unpacks them; unpacked without their post-install scripts, they give
# orterun but not the mpirun alternative, and the machine may have another mpirun):
#   bash bench/scale/multi.sh LOG GPUS [SECONDS]
set -uo pipefail
log=${1:?usage: bash bench/scale/multi.sh LOG GPUS [SECONDS]}
gpus=${2:?the number of GPUs}
secs=${3:-10}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
summary() { grep -E "frames,|GPU [0-9] \(|host merging|film reduction|ranks:|rror" || true; }
lg list | grep -A8 adapters
lg render --graph pt --scene sponza --res 1280x720 --time 5s --gpus all --out "$out/warm.exr" 2>&1 | summary
for run in "pt --layout StreamingPTmk2" "bpt-lvc"; do
  for round in 1 2; do
    echo "== $run, round $round: one GPU"
    lg render --graph $run --scene sponza --res 1280x720 --time "${secs}s" --out "$out/one.exr" 2>&1 | summary
    echo "== $run, round $round: --gpus all"
    lg render --graph $run --scene sponza --res 1280x720 --time "${secs}s" --gpus all --out "$out/all.exr" 2>&1 | summary
    echo "== $run, round $round: orterun -n $gpus --mpi"
    bash .gpu/run.sh orterun --allow-run-as-root --oversubscribe -n "$gpus" lightgraph render --mpi --graph $run \
      --scene sponza --res 1280x720 --time "${secs}s" --out "$out/mpi.exr" 2>&1 | summary
  done
done
