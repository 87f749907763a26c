#!/usr/bin/env bash
# Trace-only rates (docs/performance.md, "Trace-only rates"; issue 43, item 1): graphs/trace.ron
# on SCENES (default sponza) at 1280x720 with SPP camera rays a pixel (default "1 4"), with each
# BVH, each workgroup size of WORKGROUPS (default 64) and the CWBVH child loop unrolled and by
# bit scan (CWBVH_CHILD_SCAN false, true), with SORT set also the diffuse rays sorted by
# direction first and by origin first (TRACE_SORT), FRAMES frames a run (default 60; the rays
# are made in the first and cast in every one). A line per run: Mrays/s of camera, ambient-occlusion
# and diffuse-bounce rays over their kernel's GPU time, and the rays a frame. Then PT's
# default render of each scene for its rays/s (wall-clock and over GPU time). On the GPU machine
# from the repo root with carry [".gpu"] after `../shared/tools/gpu-bundle.sh --scene CrytekSponza`:
#   bash bench/traversal/trace.sh          (RES, default 1280x720, changes the resolution)
#   SCENES="sponza cornell-mitsuba" SPP=1 WORKGROUPS="64 128 256" bash bench/traversal/trace.sh
set -uo pipefail
source "$(dirname "$0")/../common.sh"
out=$(mktemp -d)
frames=${FRAMES:-60}
# trace_rates LABEL RENDER_ARGS...: one render of the trace graph, one line of rates.
trace_rates() {
  local label=$1
  shift
  lg render --graph trace --res ${RES:-1280x720} --frames "$frames" --out "$out/t.exr" --force "$@" >"$out/log" 2>&1 \
    || { echo "$label: failed: $(grep -m1 rror "$out/log")"; return; }
  awk -v label="$label" '
    function num(v, u) { return v * (u ~ /^G/ ? 1e9 : u ~ /^M/ ? 1e6 : u ~ /^k/ ? 1e3 : 1) }
    /^per frame:/ { for (i = 3; i <= NF; i++) if ($i ~ /^rays_/) rays[$i] = num($(i + 1), $(i + 2)) }
    /^GPU time per frame:/ { for (i = 5; i <= NF; i++) if ($i ~ /^k[0-9]+_trace_/) { k = $i; sub(/^k[0-9]+_/, "", k); ms[k] = $(i + 1) } }
    END {
      printf "%s: camera %.0f, AO %.0f, diffuse %.0f Mrays/s (%.2f, %.2f, %.2f M rays a frame; %.3f, %.3f, %.3f ms)\n", label,
        rays["rays_primary"] / ms["trace_primary"] / 1e3, rays["rays_occlusion"] / ms["trace_ao"] / 1e3,
        rays["rays_diffuse"] / ms["trace_diffuse"] / 1e3, rays["rays_primary"] / 1e6, rays["rays_occlusion"] / 1e6,
        rays["rays_diffuse"] / 1e6, ms["trace_primary"], ms["trace_ao"], ms["trace_diffuse"]
    }' "$out/log"
}
for scene in ${SCENES:-sponza}; do
  for spp in ${SPP:-1 4}; do
    for bvh in cwbvh bvh2; do
      for wg in ${WORKGROUPS:-64}; do
        trace_rates "$scene ${spp}spp $bvh wg $wg" --scene "$scene" --spp "$spp" --bvh "$bvh" --workgroup "$wg"
        [ "$bvh" = cwbvh ] && trace_rates "$scene ${spp}spp $bvh wg $wg child scan" --scene "$scene" --spp "$spp" \
          --bvh "$bvh" --workgroup "$wg" --set CWBVH_CHILD_SCAN=true
        if [ -n "${SORT:-}" ]; then
          trace_rates "$scene ${spp}spp $bvh wg $wg diffuse sorted, direction first" --scene "$scene" --spp "$spp" \
            --bvh "$bvh" --workgroup "$wg" --set TRACE_SORT=true
          trace_rates "$scene ${spp}spp $bvh wg $wg diffuse sorted, origin first" --scene "$scene" --spp "$spp" \
            --bvh "$bvh" --workgroup "$wg" --set TRACE_SORT=true --set TRACE_SORT_ORIGIN_FIRST=true
        fi
      done
    done
  done
  echo "== $scene: PT, default layout"
  lg render --graph pt --scene "$scene" --res ${RES:-1280x720} --time 5s --out "$out/pt.exr" --force 2>&1 | grep -E "frames,|rror"
done
