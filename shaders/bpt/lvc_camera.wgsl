// LVC-BPT's camera phase (shaders/bpt/lvc.wgsl has the light phase and the connections): camera
// sub-paths whose non-delta vertices emit a light sample's shadow ray and LVC_CONNECTIONS
// connections to cache vertices through the `shadow` stream.

// Pass `lvc_camera` (Start over PATHS): the camera ray of sample `index` (culled from the
// measuring frame).
fn lvc_camera(p: ptr<function, CameraSubpath>, index: u32) -> bool {
    var rng = rng_seed(frame.seed ^ 0x9e3779b9u, frame.index, index);
    *p = camera_subpath_start(camera_tiled_pixel(index % PIXELS), &rng);
    return true;
}

// Pass `lvc_trace` (Loop): finds the closest hit of the camera sub-path's ray.
fn lvc_trace(p: ptr<function, CameraSubpath>) -> bool {
    camera_subpath_trace(p);
    return true;
}

// Pass `lvc_vertex` (Loop): at the camera sub-path's new vertex, emission found (s = 0), a
// light sampled directly (s = 1) and LVC_CONNECTIONS connections to cache vertices (s >= 2),
// each MIS-weighted; then the next direction.
fn lvc_vertex(p: ptr<function, CameraSubpath>) -> bool {
    let counts = mis_counts(lvc_eta());
    let visit = camera_visit(p, counts);
    if (!visit.alive) {
        return false;
    }
    var rng = visit.rng;
    lvc_shadow_rays(*p, visit, counts, true, &rng);
    let alive = camera_scatter(p, visit.a, counts, &rng);
    (*p).rng = rng;
    return alive;
}

// The shadow rays of camera vertex `visit` of sub-path `p`, emitted through the `shadow`
// stream at one place (a fused `shadow` then inlines one traversal): with `connect`, at a
// non-delta vertex, `lvc_connections()` connections (`lvc_connection`, one random number
// each, drawn even when the cache is empty), then the s = 1 ray, if any.
fn lvc_shadow_rays(p: CameraSubpath, visit: CameraVisit, counts: MisCounts, connect: bool, rng: ptr<function, u32>) {
    let n = lvc_connections_at(visit, connect);
    let m = lvc_cached();
    for (var k = 0u; k <= n; k += 1u) {
        var ray = visit.direct;
        if (k < n) {
            ray = lvc_connection(p, visit, counts, m, rng_f32(rng));
        }
        if (!is_black(ray.contribution)) {
            emit_shadow(ray);
        }
    }
}
