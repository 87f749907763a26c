#!/usr/bin/env bash
# lightgraph vs Mitsuba 3 on Mitsuba's Cornell box (SCENE=cornell) or on Crytek Sponza
# (SCENE=sponza), the whole comparison in one run on the GPU machine (see bench/peers/README.md).
# From the repo root, with carry [".gpu", ".whl"], or [".peers.tar.xz"] made by bench/peers/pack.sh
# (Sponza: the .gpu bundle with --scene CrytekSponza, which only fits packed):
#
#   bash bench/peers/run_gpu.sh $OUT 10
#   SCENE=sponza bash bench/peers/run_gpu.sh $OUT 10
#
#   $1  output folder (default $OUT)        $2  equal-time budget in seconds (default 10)
# Environment: LAYOUT (lightgraph layout, default NaivePTsk), REF_SECONDS (reference length,
# default 120), REF_SEED (reference seed, default 7777: not the equal-time run's seed 1, so that
# the two are independent), LG_SPP (lightgraph spp per frame, default 4), SPP_PER_PASS (Mitsuba
# spp per pass, default 16), RES (default 1280x720), VARIANT (Mitsuba variant, default
# cuda_ad_rgb; another only to test the script elsewhere), KEEP_EXR (1: move the four EXRs into the
# output folder, default 1), WORK (scratch folder, default /tmp/peers-work), SCENE (cornell: Mitsuba's
# mi.cornell_box() against lightgraph's cornell-mitsuba; sponza: lightgraph's sponza-mitsuba, exported
# to Mitsuba XML on this machine from the bundled glTF), LG (the command that runs lightgraph,
# default "bash .gpu/run.sh lightgraph"; e.g. target/release/lightgraph to test the script here),
# PYTHON (default python3), LG_SET (one NAME=VALUE lightgraph constant for its runs, e.g.
# FRAMES_AT_ONCE=4; default none), LG_ARGS (more lightgraph render arguments for its runs, split
# at spaces, e.g. "--threads 8388608"; default none).
#
# The output folder gets at most 8 files (what the device tool brings back): summary.md,
# results.json, run.log, reference.png, and with KEEP_EXR=1 reference.exr, lightgraph.exr,
# mitsuba-megakernel.exr, mitsuba-wavefront.exr (about 11 MB each). With defaults it takes about
# 3-4 minutes (120 s reference, 3 x 10 s equal-time runs, Mitsuba's kernel compilation, install).
set -uo pipefail

out=${1:-${OUT:-}}
secs=${2:-10}
[ -n "$out" ] || { echo "usage: bash bench/peers/run_gpu.sh OUT_DIR [SECONDS]  (or set OUT)" >&2; exit 2; }
[[ $secs =~ ^[1-9][0-9]*$ ]] || { echo "run_gpu.sh: seconds must be a whole number, got '$secs'" >&2; exit 2; }
LAYOUT=${LAYOUT:-NaivePTsk}
REF_SECONDS=${REF_SECONDS:-120}
REF_SEED=${REF_SEED:-7777}
LG_SPP=${LG_SPP:-4}
SPP_PER_PASS=${SPP_PER_PASS:-16}
RES=${RES:-1280x720}
VARIANT=${VARIANT:-cuda_ad_rgb}
KEEP_EXR=${KEEP_EXR:-1}
work=${WORK:-/tmp/peers-work}
SCENE=${SCENE:-cornell}
LG=${LG:-bash .gpu/run.sh lightgraph}
PYTHON=${PYTHON:-python3}
read -r -a lg <<< "$LG"
read -r -a lg_args <<< "${LG_ARGS:-}"
case $SCENE in
  # lightgraph's scene, Mitsuba's scene arguments, light-pixel threshold, max depth, rr depth
  cornell) lg_scene=cornell-mitsuba; mi_scene=(); threshold=1.0; max_depth=8; rr_depth=5 ;;
  sponza) lg_scene=sponza-mitsuba; mi_scene=(--scene-xml "$work/export/scene.xml"); threshold=inf; max_depth=10; rr_depth=5 ;;
  *) echo "run_gpu.sh: SCENE must be cornell or sponza, got '$SCENE'" >&2; exit 2 ;;
esac

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root" || exit 1
mkdir -p "$out" || exit 1
out=$(cd "$out" && pwd)
mkdir -p "$work" || exit 1
rm -rf "$work"/*.exr "$work"/*.png "$work"/*.log "$work"/*.json "$work"/*.jsonl "$work/export"
export PYTHONUNBUFFERED=1 PIP_ROOT_USER_ACTION=ignore PIP_DISABLE_PIP_VERSION_CHECK=1
script=bench/peers/mitsuba_peer.py
failed=()
step() { echo; echo "=== $* ($(date -u +%H:%M:%S))"; }
t_start=$(date +%s)

main() {
step "setup"
if [ -f .peers.tar.xz ]; then
  # bench/peers/pack.sh: the .gpu bundle and the unpacked wheels in one tarball
  rm -rf .gpu .peers-site
  tar -xJf .peers.tar.xz || { echo "run_gpu.sh: cannot unpack .peers.tar.xz" >&2; return 1; }
  echo "unpacked .peers.tar.xz"
fi
[ "$LG" != "bash .gpu/run.sh lightgraph" ] || [ -f .gpu/run.sh ] || { echo "run_gpu.sh: .gpu/run.sh missing: bundle with ../shared/tools/gpu-bundle.sh and carry .gpu" >&2; return 1; }
device=$(nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader 2>/dev/null | head -1)
echo "device: ${device:-unknown}; scene $SCENE ($lg_scene); layout $LAYOUT ${LG_SET:+($LG_SET)} ${LG_ARGS:+($LG_ARGS)}; $RES; equal time ${secs} s; reference ${REF_SECONDS} s (seed $REF_SEED)"

mitsuba_ok=1
if "$PYTHON" -c 'import mitsuba, drjit' 2>/dev/null; then
  echo "mitsuba is already importable by $PYTHON: .whl/ not installed"
elif [ -d .peers-site/mitsuba ]; then
  export PYTHONPATH=$root/.peers-site${PYTHONPATH:+:$PYTHONPATH}
elif ls .whl/*.whl >/dev/null 2>&1; then
  if "$PYTHON" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl; then
    export PYTHONPATH=/tmp/site${PYTHONPATH:+:$PYTHONPATH}
  else
    echo "run_gpu.sh: installing the wheels from .whl/ failed: Mitsuba runs skipped" >&2
    mitsuba_ok=0; failed+=("wheel install")
  fi
else
  echo "run_gpu.sh: no wheels in .whl/ (run bench/peers/prepare_wheels.sh here and carry .whl): Mitsuba runs skipped" >&2
  mitsuba_ok=0; failed+=("no wheels")
fi
# Dr.Jit looks for libcuda.so (unversioned) and libnvoptix.so.1; point it at the driver's files
# when the loader does not know them by those names.
find_lib() { # $1 = file name pattern
  ldconfig -p 2>/dev/null | awk -v p="$1" '$1 ~ p { print $NF; exit }'
}
if [ -z "${DRJIT_LIBCUDA_PATH:-}" ] && [ -z "$(find_lib '^libcuda[.]so$')" ]; then
  lib=$(find_lib '^libcuda[.]so[.]1$')
  [ -n "$lib" ] || lib=$(ls /usr/local/nvidia/lib64/libcuda.so.1 /usr/local/nvidia/lib/libcuda.so.1 /usr/lib64/libcuda.so.1 2>/dev/null | head -1)
  [ -n "$lib" ] && export DRJIT_LIBCUDA_PATH=$lib && echo "DRJIT_LIBCUDA_PATH=$lib"
fi
if [ -z "${DRJIT_LIBOPTIX_PATH:-}" ] && [ -z "$(find_lib '^libnvoptix[.]so[.]1$')" ]; then
  lib=$(ls /usr/local/nvidia/lib64/libnvoptix.so.1 /usr/local/nvidia/lib/libnvoptix.so.1 /usr/lib64/libnvoptix.so.1 2>/dev/null | head -1)
  [ -n "$lib" ] && export DRJIT_LIBOPTIX_PATH=$lib && echo "DRJIT_LIBOPTIX_PATH=$lib"
fi

if [ "$SCENE" = sponza ]; then
  step "export $lg_scene to Mitsuba 3 at $RES"
  "${lg[@]}" export --format mitsuba --scene "$lg_scene" --res "$RES" --out "$work/export" \
    || { failed+=("export"); mitsuba_ok=0; }
fi

run_lightgraph() { # $1 = name, $2 = seconds, $3 = seed
  "${lg[@]}" render --scene "$lg_scene" --res "$RES" --layout "$LAYOUT" \
    --spp "$LG_SPP" --time "${2}s" --seed "$3" ${LG_SET:+--set "$LG_SET"} "${lg_args[@]}" --out "$work/$1.exr" 2>"$work/$1.log"
  local rc=$?
  cat "$work/$1.log"
  grep -q 'samples/s' "$work/$1.log" && [ $rc = 0 ] && [ -f "$work/$1.exr" ] || { failed+=("lightgraph $1 (rc $rc)"); return 1; }
}

step "(a) lightgraph reference: $LAYOUT, ${REF_SECONDS} s"
run_lightgraph reference "$REF_SECONDS" "$REF_SEED"

step "(b) lightgraph at equal time: $LAYOUT, ${secs} s"
run_lightgraph lightgraph "$secs" 1

for mode in megakernel wavefront; do
  step "(c) Mitsuba $VARIANT $mode at equal time: ${secs} s in passes of $SPP_PER_PASS spp"
  if [ $mitsuba_ok = 1 ]; then
    "$PYTHON" "$script" render ${mi_scene[@]+"${mi_scene[@]}"} --variant "$VARIANT" --mode "$mode" --res "$RES" --spp-per-pass "$SPP_PER_PASS" \
      --seconds "$secs" --out "$work/mitsuba-$mode.exr" >"$work/mitsuba-$mode.json"
    rc=$?
    cat "$work/mitsuba-$mode.json"
    [ $rc = 0 ] || failed+=("mitsuba $mode (rc $rc)")
  fi
done

step "(d) RMSE against the reference"
images=()
for name in lightgraph mitsuba-megakernel mitsuba-wavefront; do
  [ -f "$work/$name.exr" ] && images+=(--image "$name=$work/$name.exr")
done
if [ $mitsuba_ok = 1 ] && [ -f "$work/reference.exr" ] && [ ${#images[@]} -gt 0 ]; then
  "$PYTHON" "$script" rmse --emitter-threshold "$threshold" --reference "$work/reference.exr" "${images[@]}" | tee "$work/rmse.jsonl"
  [ "${PIPESTATUS[0]}" = 0 ] || failed+=("rmse")
else
  echo "skipped: needs the wheels (mitsuba reads the EXRs), the reference and at least one image"
fi

step "(e) summary"
"$PYTHON" "$script" summary --res "$RES" --seconds "$secs" --layout "$LAYOUT${LG_SET:+, $LG_SET}${LG_ARGS:+, $LG_ARGS}" \
  --title "lightgraph vs Mitsuba 3 on $lg_scene" --max-depth "$max_depth" --rr-depth "$rr_depth" \
  --lightgraph-log "$work/lightgraph.log" --reference-log "$work/reference.log" \
  --mitsuba-json "$work/mitsuba-megakernel.json" --mitsuba-json "$work/mitsuba-wavefront.json" \
  --rmse-json "$work/rmse.jsonl" --device "${device:-unknown}" \
  --out "$out/summary.md" --json-out "$out/results.json" >/dev/null || failed+=("summary")
if [ ${#failed[@]} -gt 0 ]; then
  printf '\n**Failed steps:** %s (see run.log)\n' "$(IFS=';'; echo "${failed[*]}")" >> "$out/summary.md"
fi
cat "$out/summary.md"

[ -f "$work/reference.png" ] && cp "$work/reference.png" "$out/"
if [ "$KEEP_EXR" = 1 ]; then
  for name in reference lightgraph mitsuba-megakernel mitsuba-wavefront; do
    [ -f "$work/$name.exr" ] && mv "$work/$name.exr" "$out/"
  done
fi
echo "total $(( $(date +%s) - t_start )) s; files in $out: $(ls "$out" | tr '\n' ' ')"
[ ${#failed[@]} = 0 ] || { echo "failed: ${failed[*]}" >&2; return 1; }
}

main 2>&1 | tee "$out/run.log"
exit "${PIPESTATUS[0]}"
