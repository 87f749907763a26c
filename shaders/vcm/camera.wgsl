// VCM's camera phase (shaders/vcm/vcm.wgsl has the light phase, the grid and the merges):
// camera sub-paths that make LVC-BPT's connections (shaders/bpt/lvc_camera.wgsl) and merge,
// in `vcm_vertex` (VCM_MERGE_AT_VERTEX) or in a pass of their own (`vcm_gather`).

const VCM_PENDING: u32 = 1u;    // a merge waits at the vertex below (`merge`)
const VCM_ALIVE: u32 = 2u;      // the sub-path goes on after this vertex

// A camera sub-path of VCM between passes, with the merge pending at its last vertex (its
// PendingMerge carries d_vc there, and `merge_d_vcm` d_vcm), and the frame's iteration it
// belongs to (`vcm_iteration`).
struct VcmPath {
    camera: CameraSubpath,
    merge: PendingMerge,
    merge_d_vcm: f32,
    flags: u32,
    iteration: u32,
}

// Pass `vcm_camera` (Start over PATHS): LVC-BPT's camera ray of sample `index`.
fn vcm_camera(p: ptr<function, VcmPath>, index: u32) -> bool {
    var rng = rng_seed(frame.seed ^ 0x9e3779b9u, frame.index, index);
    (*p).camera = camera_subpath_start(camera_tiled_pixel(index % PIXELS), &rng);
    (*p).flags = 0u;
    (*p).iteration = vcm_iteration(index);
    return true;
}

// Pass `vcm_trace` (Loop): the closest hit of the camera sub-path's ray.
fn vcm_trace(p: ptr<function, VcmPath>) -> bool {
    var c = (*p).camera;
    camera_subpath_trace(&c);
    (*p).camera = c;
    return true;
}

// Pass `vcm_vertex` (Loop): at the camera sub-path's new vertex, emission found (s = 0), a
// light sampled (s = 1), LVC-BPT's connections, the merge left pending for `vcm_gather`, and
// the next direction. Always true; `vcm_continue` ends the sub-path.
fn vcm_vertex(p: ptr<function, VcmPath>) -> bool {
    (*p).flags = 0u;
    let counts = vcm_counts();
    var c = (*p).camera;
    let visit = camera_visit(&c, counts);
    if (visit.alive) {
        var rng = visit.rng;
        lvc_shadow_rays(c, visit, counts, VCM_CONNECT, &rng);
        if (!visit.a.bsdf.is_delta) {
            if (VCM_MERGE) {
                let pending = pending_merge_at(visit.a.s, -c.direction, c.throughput, c.d_vc, c.length);
                if (VCM_MERGE_AT_VERTEX) {
                    vcm_merge(pending, c.d_vcm, visit.a.bsdf, (*p).iteration, c.pixel, counts);
                } else {
                    (*p).merge = pending;
                    (*p).merge_d_vcm = c.d_vcm;
                    (*p).flags = VCM_PENDING;
                }
            }
        }
        if (camera_scatter(&c, visit.a, counts, &rng)) {
            (*p).flags |= VCM_ALIVE;
        }
        c.rng = rng;
    }
    (*p).camera = c;
    return true;
}

// Pass `vcm_gather` (Loop; culled where VCM_MERGE_AT_VERTEX): the pending merge.
fn vcm_gather(p: ptr<function, VcmPath>) -> bool {
    if (((*p).flags & VCM_PENDING) != 0u) {
        vcm_merge((*p).merge, (*p).merge_d_vcm, Bsdf(), (*p).iteration, (*p).camera.pixel, vcm_counts());
    }
    return true;
}

// The merges at camera vertex `v` of `iteration` (`vcm_merged`) into `pixel`.
fn vcm_merge(v: PendingMerge, d_vcm: f32, bsdf: Bsdf, iteration: u32, pixel: u32, counts: MisCounts) {
    let radiance = vcm_merged(v, d_vcm, bsdf, iteration, counts);
    if (any(radiance != vec3<f32>(0.0))) {
        film_add(pixel, radiance);
        film_add_biased(pixel, radiance);
    }
}

// Pass `vcm_continue` (Loop, last): ends the sub-path when `vcm_vertex` said so.
fn vcm_continue(p: ptr<function, VcmPath>) -> bool {
    return ((*p).flags & VCM_ALIVE) != 0u;
}
