// Pass `bpt_vertex` (Loop): at the camera sub-path's new vertex, emission found by the path
// (s = 0), a light sampled directly (s = 1) and connections to every stored vertex of the
// sample's light sub-path (s >= 2), each MIS-weighted; then the next direction.

fn bpt_vertex(p: ptr<function, BptPath>) -> bool {
    var camera = (*p).camera;
    let c = &camera;
    let v = camera_visit(c, mis_counts(1.0));
    if (!v.alive) {
        return false;
    }
    // The s = 1 ray, then the connections, emitted at one place (a fused `shadow` then
    // inlines one any-hit traversal).
    let connections = select((*p).light_count, 0u, v.a.bsdf.is_delta);
    for (var i = 0u; i <= connections; i += 1u) {
        var ray = v.direct;
        if (i > 0u) {
            let lv = (*p).light[i - 1u];
            if (light_vertex_length(lv) + 1u + (*c).length > MAX_PATH_LENGTH) {
                break;
            }
            ray = bpt_connect(*c, v.a.s, v.a.bsdf, lv, mis_counts(1.0));
        }
        if (!is_black(ray.contribution)) {
            emit_shadow(ray);
        }
    }
    var rng = v.rng;
    let alive = camera_scatter(c, v.a, mis_counts(1.0), &rng);
    (*c).rng = rng;
    (*p).camera = camera;
    return alive;
}
