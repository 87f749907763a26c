#!/usr/bin/env bash
# The fidelity suite at full size on the GPU machine: Mitsuba 3 (cuda_ad_rgb) and lightgraph
# render every scene of bench/peers/fidelity/scenes there, and fidelity.py compares them.
# Run HERE first (docs/mitsuba.md, "The fidelity suite"):
#
#   bash bench/peers/prepare_wheels.sh
#   cargo build --release && ../shared/tools/gpu-bundle.sh && strip .gpu/bin/lightgraph && bash bench/peers/pack.sh
#
# then on the GPU machine, carry [".peers.tar.xz"]:
#
#   bash bench/peers/fidelity/gpu.sh $OUT
#
# Environment: RES (default 256x256), SPP (Mitsuba's samples per pixel a pass, default 1024),
# PASSES (Mitsuba's passes, default 16), SECONDS_LG (lightgraph's time a scene, default 8),
# SCENES (scene files, default every one of the suite), VARIANT (default cuda_ad_rgb), LG (the
# command that runs lightgraph, default "bash .gpu/run.sh lightgraph"; target/release/lightgraph
# to try the script here with VARIANT=llvm_ad_rgb), VERIFY_SCENES and VERIFY_TIME (`lightgraph
# verify` of every estimator on those scenes at 128 x 128; default none), FIDELITY (0: only the
# verify run).
# $OUT gets fidelity.md (the table), maps.tgz (each scene's map of its blocks' z, PNG and CSV),
# verify.md when asked, and logs.tgz.
set -uo pipefail
out=${1:?usage: gpu.sh OUT_DIR}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../../.." && pwd)
cd "$root" || exit 1
mkdir -p "$out" && out=$(cd "$out" && pwd)
work=${WORK:-/tmp/fidelity}
mkdir -p "$work/ref" "$work/lg"
if [ -f .peers.tar.xz ] && [ ! -d .peers-site ]; then
  tar -xJf .peers.tar.xz || { echo "cannot unpack .peers.tar.xz" >&2; exit 1; }
fi
export PYTHONPATH=$root/.peers-site${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
lib=$(ldconfig -p 2>/dev/null | awk '$1 ~ /^libcuda[.]so[.]1$/ { print $NF; exit }')
[ -n "$lib" ] && [ -z "$(ldconfig -p | awk '$1 ~ /^libcuda[.]so$/')" ] && export DRJIT_LIBCUDA_PATH=$lib
LG=${LG:-bash .gpu/run.sh lightgraph}
read -r -a lg <<< "$LG"
read -r -a scenes <<< "${SCENES:-}"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$work/device.txt"
if [ "${FIDELITY:-1}" != 0 ]; then
  t0=$SECONDS
  python3 bench/peers/fidelity/fidelity.py reference "${scenes[@]}" --out "$work/ref" --res "${RES:-256x256}" \
    --spp "${SPP:-1024}" --passes "${PASSES:-16}" --variant "${VARIANT:-cuda_ad_rgb}" 2>&1 | tee "$work/mitsuba.log"
  echo "mitsuba: $((SECONDS - t0)) s"
  t0=$SECONDS
  python3 bench/peers/fidelity/fidelity.py lightgraph "${scenes[@]}" --out "$work/lg" --res "${RES:-256x256}" \
    --time "${SECONDS_LG:-8}s" --bin "${lg[-1]}" --runner "${lg[*]:0:${#lg[@]}-1}" 2>&1 | tee "$work/lightgraph.log"
  echo "lightgraph: $((SECONDS - t0)) s"
  python3 bench/peers/fidelity/fidelity.py compare "$work/ref" "$work/lg" --maps "$work/maps" | tee "$out/fidelity.md"
  (cd "$work" && tar -czf "$out/maps.tgz" maps)
fi
if [ -n "${VERIFY_SCENES:-}" ]; then
  "${lg[@]}" verify --scenes "$VERIFY_SCENES" --res 128x128 --time "${VERIFY_TIME:-4s}" --out "$work/verify" \
    > "$work/verify.log" 2>&1
  tail -3 "$work/verify.log"
  cp "$work/verify/verify.md" "$out/verify.md" 2>/dev/null
fi
(cd "$work" && tar -czf "$out/logs.tgz" ./*.log device.txt lg/*.log verify/verify.csv 2>/dev/null)
ls -la "$out"
