#!/usr/bin/env bash
# Checks a SmallUPBP build: renders scene 0 (an absorbing sphere in the Cornell box) at 64x64
# on one thread with its volumetric path tracer, its volumetric BPT and full UPBP, reads the
# EXRs (exr_image.py) and fails unless each image is finite, not all zero, and its mean per
# channel lies within TOL (default 0.02, relative) of the path tracer's.
#
#   bench/peers/smallupbp/smoke.sh [SMALLUPBP_BINARY] [OUT_DIR]
#
# Defaults: bench/peers/smallupbp/build/SmallUPBP, a fresh temporary folder.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
bin=${1:-$here/build/SmallUPBP}
out=${2:-$(mktemp -d)}
TOL=${TOL:-0.02}
[ -x "$bin" ] || { echo "smoke.sh: $bin: no SmallUPBP executable (run build.sh)" >&2; exit 2; }
mkdir -p "$out"
for run in "vptmis 64" "upbp_bpt 16" "upbp_all 16"; do
    set -- $run
    OMP_NUM_THREADS=1 "$bin" -s 0 -a "$1" -r 64x64 -i "$2" -th 1 -o "$out/s00-$1.exr" \
        | grep 'done in' | sed "s/^/smoke.sh: -a $1 -i $2: /"
    python3 "$here/exr_image.py" "$out/s00-$1.exr" > /dev/null
done
python3 - "$here" "$out" "$TOL" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import exr_image

out, tol = sys.argv[2], float(sys.argv[3])
means = {a: {c: exr_image.read(f"{out}/s00-{a}.exr")[c].mean() for c in "RGB"}
         for a in ("vptmis", "upbp_bpt", "upbp_all")}
ok = True
for a in ("upbp_bpt", "upbp_all"):
    for c in "RGB":
        rel = means[a][c] / means["vptmis"][c] - 1
        print(f"smoke.sh: {a} {c} mean {means[a][c]:.5f} vs vptmis {means['vptmis'][c]:.5f} ({rel:+.2%})")
        ok &= abs(rel) <= tol
sys.exit(0 if ok else f"smoke.sh: a mean differs from the path tracer's by more than {tol:.1%}")
PY
echo "smoke.sh: ok ($out)"
