#!/usr/bin/env bash
# Scale-out on one machine (docs/performance.md, "Scale-out on one machine"): PT (StreamingPTmk2)
# and LVC-BPT (LVC-BPTsk) on Sponza at 1280x720 for SECONDS each: on one GPU in one process,
# on N GPUs in one process (--gpus N) and with N MPI ranks (--mpi, one GPU each), for every N
# in GPU_COUNTS, after a warm-up of every GPU; two rounds. MPI runs through the machine's own
# mpirun (Open MPI 4.1.6 on the GPU machine's image), whose lib folder goes on
# LD_LIBRARY_PATH for the binary's libmpi. The summary lines give samples/s (set-up off the
# clock), frames per GPU or rank, the host's merge time and the film reduction's time. Run on a
# multi-GPU kind from the repo root with carry [".gpu"] and a binary built with --features mpi:
#   bash bench/scale/multi.sh LOG "GPU_COUNTS" [SECONDS]      e.g.  bash bench/scale/multi.sh $OUT/multi.log "2 4" 10
# (SCENE and RES, default sponza and 1280x720, change the scene and the resolution.)
set -uo pipefail
log=${1:?usage: bash bench/scale/multi.sh LOG GPU_COUNTS [SECONDS]}
counts=${2:?the GPU counts, e.g. "2 4"}
secs=${3:-10}
scene=${SCENE:-sponza} res=${RES:-1280x720}
exec > >(tee "$log") 2>&1
out=$(mktemp -d)
source "$(dirname "$0")/../common.sh"
mpi=$(command -v mpirun) || { echo "no mpirun on the PATH"; exit 1; }
export LD_LIBRARY_PATH=$(dirname "$(dirname "$mpi")")/lib:${LD_LIBRARY_PATH:-}
"$mpi" --version | head -1
summary() { grep -E "frames,|frames by rank|GPU [0-9] \(|host merging|film reduction|rror" || true; }
ranks() {
  local n=$1
  shift
  bash .gpu/run.sh "$mpi" --allow-run-as-root --oversubscribe --bind-to none -n "$n" -x LD_LIBRARY_PATH \
    lightgraph render --mpi "$@"
}
lg list | grep -A8 adapters
lg render --graph pt --scene "$scene" --res "$res" --time 5s --gpus all --out "$out/warm.exr" --force 2>&1 | summary
for run in "pt --layout StreamingPTmk2" "bpt-lvc --layout LVC-BPTsk"; do
  for round in 1 2; do
    echo "== $run, round $round: one GPU"
    lg render --graph $run --scene "$scene" --res "$res" --time "${secs}s" --out "$out/one.exr" --force 2>&1 | summary
    for n in 1 $counts; do
      echo "== $run, round $round: mpirun -n $n --mpi"
      ranks "$n" --graph $run --scene "$scene" --res "$res" --time "${secs}s" --out "$out/mpi.exr" --force 2>&1 | summary
    done
    for n in $counts; do
      echo "== $run, round $round: --gpus $n"
      lg render --graph $run --scene "$scene" --res "$res" --time "${secs}s" --gpus "$n" --out "$out/all.exr" --force 2>&1 | summary
    done
  done
done
