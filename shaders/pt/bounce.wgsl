// A camera path's bounce, as functions of the random numbers they use: next-event estimation
// (`material_next_event`) and the BSDF sample with Russian roulette (`material_scatter`). The
// pass `material` draws the numbers from the path's stream; a Markov chain over primary
// samples (shaders/mlt/path.wgsl) draws them from its chain, so both evaluate the same
// estimator.

// The factor of the continuation probability in the BSDF densities used for MIS: with the
// albedo roulette rule (RR_ALBEDO) they include it, as in SmallVCM; with the throughput rule
// (Mitsuba's) they do not.
fn material_mis_continuation(bsdf: Bsdf) -> f32 {
    return select(1.0, bsdf.continuation, RR_ALBEDO);
}

// Next-event estimation at the path's vertex `v`: a light picked with `light_u`, a point on
// it with `light_uv`, and the shadow ray carrying the MIS-weighted contribution (black: no
// ray to trace).
fn material_next_event(path: CameraPath, v: PathVertex, light_u: f32, light_uv: vec2<f32>) -> ShadowRay {
    let s = v.s;
    let bsdf = v.bsdf;
    let none = ShadowRay();
    if (bsdf.is_delta || scene.num_lights == 0u) {
        return none;
    }
    let picked = pick_light(light_u);
    let pick = picked.probability;
    let ill = illuminate(picked.index, s.position, light_uv);
    if (is_black(ill.radiance)) {
        return none;
    }
    let e = bsdf_eval(bsdf, ill.direction);
    if (is_black(e.f)) {
        return none;
    }
    var w = 1.0;
    if (!ill.is_delta) {
        w = mis_weight(ill.pdf * pick, e.pdf_forward * material_mis_continuation(bsdf));
    }
#if MEDIA
    var ray = light_sample_ray(s, ill, path.pixel, path.throughput * ill.radiance * e.f * (w * e.cos_gen / (pick * ill.pdf)));
    ray.medium = medium_after(s.material, s.normal, ill.direction, path.medium);
    return ray;
#else
    return light_sample_ray(s, ill, path.pixel, path.throughput * ill.radiance * e.f * (w * e.cos_gen / (pick * ill.pdf)));
#endif
}

// The path's next direction from the BSDF at `v` (sampled with `u`), then Russian roulette
// with `roulette_u`; false when the path ends.
fn material_scatter(path: ptr<function, CameraPath>, v: PathVertex, u: vec3<f32>, roulette_u: f32) -> bool {
    let s = v.s;
    let bsdf = v.bsdf;
    let smp = bsdf_sample(bsdf, u);
    if (is_black(smp.f)) {
        return false;
    }
    let throughput = (*path).throughput * smp.f * (smp.cos_gen / smp.pdf);
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
    (*path).last_pdf = smp.pdf * material_mis_continuation(bsdf);
    (*path).last_specular = select(0u, 1u, smp.specular);
    (*path).origin = offset_ray_origin(s.position, side_normal(s.normal, smp.direction), s.extent);
    (*path).direction = smp.direction;
#if MEDIA
    (*path).medium = medium_after(s.material, s.normal, smp.direction, (*path).medium);
    (*path).gap = 0.0;
#endif
    return true;
}
