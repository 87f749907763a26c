# Shared by the GPU bench scripts of bench/TOPIC/ (each sources it as "$(dirname "$0")/../common.sh";
# they run from the repo root on the GPU machine, where .gpu/run.sh is; bench/README.md): lightgraph
# through the GPU bundle, one 1280x720 render's rates, per-frame counters and GPU time per
# kernel (`render_summary`, needs $out, a scratch folder), one `bench` run's rows
# (`bench_rows`), issue 13's VCM rows (`vcm_rows`), and PPMsk's camera kernel (`ppm_camera`).
lg() { bash .gpu/run.sh lightgraph "$@"; }
# render_summary FRAMES ARGS...
render_summary() {
  local frames=$1
  shift
  echo "== $*"
  lg render --res 1280x720 --frames "$frames" --out "$out/x.exr" "$@" 2>&1 | grep -E "frames,|per frame|GPU time|rror"
}
# bench_rows BINARY LABEL BENCH_ARGS...: one `bench` run with the bundle's BINARY, then a line
# per layout: LABEL, layout, WxHxSPP, frames/s, Msamples/s, Mrays/s wall-clock and of GPU time,
# and the GPU ms a frame of the kernels whose names match $KERNELS (grep -E; none when unset).
bench_rows() {
  local bin=$1 label=$2 dir
  shift 2
  dir=$(mktemp -d)
  bash .gpu/run.sh "$bin" bench --out "$dir" "$@" >/dev/null 2>&1 || { echo "$label: failed"; return; }
  tail -n +2 "$dir/bench.csv" | while IFS=, read -r layout w h spp paths frames secs rays rps grps sps fps mem kms; do
    local kernels=""
    [ -n "${KERNELS:-}" ] && kernels=$(echo "$kms" | tr ';' '\n' | grep -E "$KERNELS" | tr '\n' ' ')
    echo "$label,$layout,${w}x${h}x$spp,$fps frames/s,$(awk "BEGIN { printf \"%.1f Msamples/s,%.0f Mrays/s,%.0f GPU Mrays/s\", $sps / 1e6, $rps / 1e6, $grps / 1e6 }")${kernels:+,$kernels}"
  done
  rm -rf "$dir"
}
# vcm_rows BINARY LABEL: `bench_rows` of LVC-BPTsk, VCMsk and VCMmk on Sponza at 1280x720x1 and of
# VCMsk on the diffuse box at 256x256 with 64 iterations a frame (issue 13's two rates), 2 s a point.
vcm_rows() {
  bench_rows "$1" "$2 sponza" --time 2s --scene sponza --graph bpt-lvc --layouts LVC-BPTsk --points 1280x720x1
  bench_rows "$1" "$2 sponza" --time 2s --scene sponza --graph vcm --layouts VCMsk,VCMmk --points 1280x720x1
  bench_rows "$1" "$2 box" --time 2s --scene cornell-diffuse --graph vcm --layouts VCMsk \
    --points 256x256x64 --set PM_ITERATIONS=64
}
# ppm_camera BINARY ARGS...: a 60-frame PPMsk render (or $PM_GRAPH in $PM_LAYOUT) at 1280x720
# with the bundle's BINARY (scene and constants in ARGS), on one line: photons found, queries and queries split a
# frame, and the GPU ms a frame of the light and camera kernels, of the split queries' parts and
# of the engine's operators (the grid's build, the split queries' scan).
ppm_camera() {
  bash .gpu/run.sh "$1" render --graph "${PM_GRAPH:-ppm}" --layout "${PM_LAYOUT:-PPMsk}" --res 1280x720 --frames 60 "${@:2}" --out /tmp/x.exr 2>&1 |
    grep -oE "pm_(found|queries|split|split_parts) [0-9.]* [kM]?|k[0-9]+_(pm_light[a-z_]*|[a-z]+_camera[a-z_]*|grid_split_gather) [0-9.]* ms|lg_op[0-9]+_[a-z0-9]+ [0-9.]* ms" | tr '\n' ' '
}
