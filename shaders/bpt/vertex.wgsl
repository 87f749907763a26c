// Pass `bpt_vertex` (Loop): at the camera sub-path's new vertex, emission found by the path
// (s = 0), a light sampled directly (s = 1) and connections to every stored vertex of the
// sample's light sub-path (s >= 2), each MIS-weighted; then the next direction.

fn bpt_vertex(p: ptr<function, BptPath>) -> bool {
    var camera = (*p).camera;
    let c = &camera;
    let a = camera_arrive(c, 1.0);
    if (!a.alive) {
        return false;
    }
    let s = a.s;
    let bsdf = a.bsdf;
    var rng = (*c).rng;
    let light_u = rng_f32(&rng);
    let light_uv = rng_vec2(&rng);
    if ((*c).length >= MAX_PATH_LENGTH) {
        return false;
    }
    if (!bsdf.is_delta) {
        if (scene.num_lights > 0u) {
            let ray = bpt_direct(*c, s, bsdf, light_u, light_uv);
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
        for (var i = 0u; i < (*p).light_count; i += 1u) {
            let v = (*p).light[i];
            if (light_vertex_length(v) + 1u + (*c).length > MAX_PATH_LENGTH) {
                break;
            }
            let ray = bpt_connect(*c, s, bsdf, v, 1.0);
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
    }
    let alive = camera_scatter(c, a, 1.0, &rng);
    (*c).rng = rng;
    (*p).camera = camera;
    return alive;
}
