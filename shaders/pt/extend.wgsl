// Pass `extend` (Loop): traces the path's ray, adds emission found there (MIS-weighted
// against light sampling), emits a shadow ray for next-event estimation, and samples the
// next direction, with Russian roulette. Returns false when the path ends.
//
// MIS (two strategies for lights of finite extent): a light hit by BSDF sampling with
// density p_bsdf is weighted w(p_bsdf, p_light * pick); a light sampled directly with
// density p_light is weighted w(p_light * pick, p_bsdf). With the albedo roulette rule,
// p_bsdf includes the continuation probability, as in SmallVCM.

fn extend(path: ptr<function, CameraPath>) -> bool {
    let o = (*path).origin;
    let d = (*path).direction;
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*path).length == 0u), 1u);
    let hit = trace_closest(o, d, INFINITE_DISTANCE);
    (*path).length += 1u;
    let pick = light_pick_probability();
    if (!hit.found) {
        let bg = background_radiance();
        if (bg.w > 0.0) {
            var w = 1.0;
            if ((*path).last_specular == 0u) {
                w = mis_weight((*path).last_pdf, bg.w * pick);
            }
            film_add((*path).pixel, (*path).throughput * w * bg.xyz);
        }
        return false;
    }
    let s = surface_at(hit, o, d);
    let bsdf = bsdf_setup(s.material, s.normal, -d);
    if (!bsdf.valid) {
        return false;
    }
    if (s.light >= 0) {
        let le = area_light_radiance(u32(s.light), d);
        if (le.w > 0.0) {
            var w = 1.0;
            if ((*path).last_specular == 0u) {
                let light_pdf = le.w * hit.t * hit.t / abs(bsdf.fix.z);
                w = mis_weight((*path).last_pdf, light_pdf * pick);
            }
            film_add((*path).pixel, (*path).throughput * w * le.xyz);
        }
    }
    if ((*path).length >= MAX_PATH_LENGTH || bsdf.continuation == 0.0) {
        return false;
    }
    var rng = (*path).rng;
    let roulette_in_mis = RR_ALBEDO;
    let q_mis = select(1.0, bsdf.continuation, roulette_in_mis);
    // Next-event estimation.
    let light_u = rng_f32(&rng);
    let light_uv = rng_vec2(&rng);
    if (!bsdf.is_delta && scene.num_lights > 0u) {
        let index = min(u32(light_u * f32(scene.num_lights)), scene.num_lights - 1u);
        let ill = illuminate(index, s.position, light_uv);
        if (!is_black(ill.radiance)) {
            let e = bsdf_eval(bsdf, ill.direction);
            if (!is_black(e.f)) {
                var w = 1.0;
                if (!ill.is_delta) {
                    w = mis_weight(ill.pdf * pick, e.pdf_forward * q_mis);
                }
                let contribution = (*path).throughput * ill.radiance * e.f * (w * e.cos_gen / (pick * ill.pdf));
                let side = select(-s.normal, s.normal, dot(s.normal, ill.direction) > 0.0);
                let origin = offset_ray_origin(s.position, side, scene.radius);
                var distance = INFINITE_DISTANCE;
                if (ill.distance < INFINITE_DISTANCE) {
                    var aim = s.position + ill.direction * ill.distance;
                    if (lights[index].kind == LIGHT_AREA) {
                        aim = offset_ray_origin(ill.point, ill.normal, scene.radius);
                    }
                    distance = length(aim - origin);
                }
                emit_shadow(ShadowRay(origin, (*path).pixel, ill.direction, distance, contribution));
            }
        }
    }
    // Continuation.
    let u = vec3<f32>(rng_vec2(&rng), rng_f32(&rng));
    let smp = bsdf_sample(bsdf, u);
    let roulette_u = rng_f32(&rng);
    (*path).rng = rng;
    if (is_black(smp.f)) {
        return false;
    }
    var throughput = (*path).throughput * smp.f * (smp.cos_gen / smp.pdf);
    var q = 1.0;
    if (RR_ALBEDO) {
        q = bsdf.continuation;
    } else if ((*path).length >= RR_START) {
        q = min(max_component(throughput), RR_MAX);
    }
    if (roulette_u >= q) {
        return false;
    }
    (*path).throughput = throughput / q;
    (*path).last_pdf = smp.pdf * q_mis;
    (*path).last_specular = select(0u, 1u, smp.specular);
    let side = select(-s.normal, s.normal, dot(s.normal, smp.direction) > 0.0);
    (*path).origin = offset_ray_origin(s.position, side, scene.radius);
    (*path).direction = smp.direction;
    return true;
}
