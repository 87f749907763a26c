#!/usr/bin/env bash
# Checks a SmallUPBP build: renders scene 1 (a sphere of isotropic scattering medium in the
# Cornell box) at 64x64 on one thread with its volumetric path tracer (vptmis), its volumetric
# BPT (upbp_bpt) and full UPBP (upbp_all: points, beams and paths), reads the EXRs
# (exr_image.py) and fails unless each image is finite and not all zero, and its mean over the
# pixels that do not see the light lies within TOL (default 0.03, relative) of the path
# tracer's, per channel. (A build with g++'s strict aliasing, for one, gives upbp_all -6.5%.)
#
#   bench/peers/smallupbp/smoke.sh [SMALLUPBP_BINARY] [OUT_DIR]
#
# Defaults: bench/peers/smallupbp/build/SmallUPBP, a fresh temporary folder. About 10 s.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
bin=${1:-$here/build/SmallUPBP}
out=${2:-$(mktemp -d)}
TOL=${TOL:-0.03}
[ -x "$bin" ] || { echo "smoke.sh: $bin: no SmallUPBP executable (run build.sh)" >&2; exit 2; }
mkdir -p "$out"
for run in "vptmis 256" "upbp_bpt 64" "upbp_all 24"; do
    set -- $run
    OMP_NUM_THREADS=1 "$bin" -s 1 -a "$1" -r 64x64 -i "$2" -th 1 -o "$out/s01-$1.exr" \
        | grep 'done in' | sed "s/^/smoke.sh: -a $1 -i $2: /"
    python3 "$here/exr_image.py" "$out/s01-$1.exr" > /dev/null
done
python3 - "$here" "$out" "$TOL" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import exr_image
import numpy as np

out, tol = sys.argv[2], float(sys.argv[3])
images = {a: np.dstack([exr_image.read(f"{out}/s01-{a}.exr")[c] for c in "RGB"])
          for a in ("vptmis", "upbp_bpt", "upbp_all")}
ref = images["vptmis"]
unlit = ref.max(axis=2) < 1.0  # the light's pixels (radiance 25) would dominate the means
ok = True
for a in ("upbp_bpt", "upbp_all"):
    rel = images[a][unlit].mean(axis=0) / ref[unlit].mean(axis=0) - 1
    print(f"smoke.sh: {a} vs vptmis, mean without the light's pixels, R G B: "
          + " ".join(f"{r:+.2%}" for r in rel))
    ok &= bool(np.all(np.abs(rel) <= tol))
sys.exit(0 if ok else f"smoke.sh: a mean differs from the path tracer's by more than {tol:.1%}")
PY
echo "smoke.sh: ok ($out)"
