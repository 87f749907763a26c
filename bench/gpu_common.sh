# Shared by the photon-mapping GPU bench scripts (sourced; needs $out, a scratch folder):
# lightgraph through the GPU bundle, and one 1280x720 render's rates, per-frame counters and
# GPU time per kernel.
lg() { bash .gpu/run.sh lightgraph "$@"; }
# render_summary FRAMES ARGS...
render_summary() {
  local frames=$1
  shift
  echo "== $*"
  lg render --res 1280x720 --frames "$frames" --out "$out/x.exr" "$@" 2>&1 | grep -E "frames,|per frame|GPU time|rror"
}
