// Pass `bpt_vertex` (Loop): at the camera sub-path's new vertex, emission found by the path
// (s = 0), a light sampled directly (s = 1) and connections to every stored vertex of the
// sample's light sub-path (s >= 2), each MIS-weighted; then the next direction.

fn bpt_vertex(p: ptr<function, BptPath>) -> bool {
    let a = camera_arrive(bpt_camera_vertex(*p), (*p).origin, (*p).direction, Hit((*p).hit_t, (*p).hit_primitive, (*p).hit_uv, true), 1.0);
    if (!a.alive) {
        return false;
    }
    (*p).d_vcm = a.d_vcm;
    (*p).d_vc = a.d_vc;
    let s = a.s;
    let bsdf = a.bsdf;
    var rng = (*p).rng;
    let light_u = rng_f32(&rng);
    let light_uv = rng_vec2(&rng);
    if ((*p).length >= MAX_PATH_LENGTH) {
        return false;
    }
    if (!bsdf.is_delta) {
        if (scene.num_lights > 0u) {
            let ray = bpt_direct(bpt_camera_vertex(*p), s, bsdf, light_u, light_uv);
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
        for (var i = 0u; i < (*p).light_count; i += 1u) {
            let v = (*p).light[i];
            if (light_vertex_length(v) + 1u + (*p).length > MAX_PATH_LENGTH) {
                break;
            }
            let ray = bpt_connect(bpt_camera_vertex(*p), s, bsdf, v, 1.0);
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
    }
    let r = scatter(bsdf, s, (*p).throughput, (*p).d_vcm, (*p).d_vc, 1.0, &rng);
    (*p).rng = rng;
    if (!r.alive) {
        return false;
    }
    (*p).origin = r.origin;
    (*p).direction = r.direction;
    (*p).throughput = r.throughput;
    (*p).d_vcm = r.d_vcm;
    (*p).d_vc = r.d_vc;
    return true;
}
