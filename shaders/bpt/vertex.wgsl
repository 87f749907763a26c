// Pass `bpt_vertex` (Loop): at the camera sub-path's new vertex, emission found by the path
// (s = 0), a light sampled directly (s = 1) and connections to every stored vertex of the
// sample's light sub-path (s >= 2), each MIS-weighted; then the next direction.

fn bpt_vertex(p: ptr<function, BptPath>) -> bool {
    if ((*p).hit_t < 0.0) {
        let bg = background_radiance((*p).direction);
        if (bg.w > 0.0) {
            let pmf = light_pmf(u32(scene.background));
            let w = bpt_hit_weight(bpt_camera_vertex(*p), bg.w * pmf, bg.w * disk_pdf(scene.radius) * pmf, 1.0);
            film_add((*p).pixel, (*p).throughput * w * bg.xyz);
        }
        return false;
    }
    let s = surface_at(Hit((*p).hit_t, (*p).hit_primitive, (*p).hit_uv, true), (*p).origin, (*p).direction);
    let bsdf = bsdf_setup(material_at(s.material, s.tex), s.normal, -(*p).direction);
    if (!bsdf.valid) {
        return false;
    }
    let t = (*p).hit_t;
    let c = mis_pow(abs(bsdf.fix.z));
    (*p).d_vcm = mis_clamp((*p).d_vcm * mis_pow(t * t) / c);
    (*p).d_vc = mis_clamp((*p).d_vc / c);
    if (s.light >= 0) {
        let le = area_light_radiance(u32(s.light), (*p).direction);
        if (le.w > 0.0) {
            let pmf = light_pmf(u32(s.light));
            let cos_light = dot(lights[u32(s.light)].normal, -(*p).direction);
            let w = bpt_hit_weight(bpt_camera_vertex(*p), le.w * pmf, le.w * cos_light * INV_PI * pmf, 1.0);
            film_add((*p).pixel, (*p).throughput * w * le.xyz);
        }
    }
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
