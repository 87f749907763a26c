#!/usr/bin/env bash
# Time to error: lightgraph's estimators against SmallUPBP's on one of SmallUPBP's scenes.
#
#   study.sh SCENE_NUMBER SCENE.ron OUT
#
# On one machine (the GPU machine: lightgraph on its GPU, SmallUPBP on its CPU cores):
#  1. a reference: lightgraph `reference` of SCENE.ron with `pt` for $REF_TIME (seed of its own);
#  2. SmallUPBP's scene SCENE_NUMBER with each algorithm of $SUP_ALGS for each budget of
#     $SUP_TIMES seconds (`-t`) on $THREADS threads; each run's "done in T s (N iterations)" line
#     goes to OUT/sup/runs.tsv;
#  3. `lightgraph study` of SCENE.ron with $LG_ESTIMATORS for $LG_TIME each against that reference.
# Then `time_to_error.py OUT` (anywhere with numpy and OpenEXR) gives the table: each SmallUPBP
# image's RMSE against the reference and the time lightgraph's estimators took to reach it.
#
# Environment: SUP (SmallUPBP executable), LG (lightgraph; default `lightgraph` on PATH),
# RES (default 256x256), MAX_LENGTH (default 10, both sides), THREADS (default nproc),
# REF_TIME (default 120s), SUP_ALGS (default "vptmis upbp_all"), SUP_TIMES (default "2 8 32"),
# LG_ESTIMATORS (default pt), LG_TIME (default 30s).
set -euo pipefail
if [ $# -ne 3 ]; then
  echo "usage: study.sh SCENE_NUMBER SCENE.ron OUT" >&2
  exit 2
fi
scene=$1 ron=$2 out=$3
: "${SUP:?set SUP to the SmallUPBP executable (build.sh builds it)}"
LG=${LG:-lightgraph} RES=${RES:-256x256} MAX_LENGTH=${MAX_LENGTH:-10} THREADS=${THREADS:-$(nproc)}
REF_TIME=${REF_TIME:-120s} SUP_ALGS=${SUP_ALGS:-vptmis upbp_all} SUP_TIMES=${SUP_TIMES:-2 8 32}
LG_ESTIMATORS=${LG_ESTIMATORS:-pt} LG_TIME=${LG_TIME:-30s}
[ -f "$ron" ] || { echo "study.sh: $ron: no such scene file" >&2; exit 2; }
[ -x "$SUP" ] || { echo "study.sh: SUP=$SUP is not an executable" >&2; exit 2; }
stem=$(basename "$ron" .ron)
mkdir -p "$out/refs" "$out/sup"

"$LG" reference --scene "$ron" --graph pt --res "$RES" --max-path-length "$MAX_LENGTH" \
  --time "$REF_TIME" --out "$out/refs/$stem.exr" 2>&1 | tail -1

printf 'scene\talgorithm\tbudget_s\tthreads\tseconds\titerations\timage\n' >"$out/sup/runs.tsv"
for alg in $SUP_ALGS; do
  for t in $SUP_TIMES; do
    img=$alg-$t.exr
    line=$(OMP_NUM_THREADS=$THREADS "$SUP" -s "$scene" -a "$alg" -r "$RES" -l "$MAX_LENGTH" \
      -t "$t" -th "$THREADS" -o "$out/sup/$img" | grep -E "done in" | tail -1)
    # "done in 8.03 s (12 iterations)"
    secs=$(sed -E 's/.*done in ([0-9.]+) s.*/\1/' <<<"$line")
    iters=$(sed -E 's/.*\(([0-9]+) iterations?\).*/\1/' <<<"$line")
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$scene" "$alg" "$t" "$THREADS" "$secs" "$iters" "$img" \
      >>"$out/sup/runs.tsv"
    echo "SmallUPBP $alg -t $t: $line"
  done
done

# The reference holds $REF_TIME of rendering; the study takes it as it is.
"$LG" study --scenes "$ron" --estimators "$LG_ESTIMATORS" --res "$RES" \
  --max-path-length "$MAX_LENGTH" --time "$LG_TIME" --references "$out/refs" \
  --reference-time 1s --out "$out/study" --force 2>&1 | tail -2
