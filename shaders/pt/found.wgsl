// What a camera path's traced ray found, as functions: the background behind an escaped ray
// and the emission of an area light it hit, each MIS-weighted against light sampling (a light
// hit by BSDF sampling with density p_bsdf is weighted w(p_bsdf, p_light * pick), pick being
// the light's selection probability, `light_pmf`; the same light sampled directly in
// `material_next_event`, shaders/pt/bounce.wgsl, is weighted w(p_light * pick, p_bsdf)). Used
// by the pass `logic` and by Markov chains over primary samples (shaders/mlt/path.wgsl).

// The background seen by the path's escaped ray, MIS-weighted against light sampling.
fn path_background_found(path: CameraPath) -> vec3<f32> {
    let bg = background_radiance(path.direction);
    if (is_black(bg.xyz)) {
        return vec3<f32>(0.0);
    }
    var w = 1.0;
    if (path.last_specular == 0u) {
        w = mis_weight(path.last_pdf, bg.w * light_pmf(u32(scene.background)));
    }
    return path.throughput * w * bg.xyz;
}

// The emission of the area light the path's ray hit at surface `s` (with BSDF `bsdf`),
// MIS-weighted against light sampling; black where `s` is no light.
fn path_light_found(path: CameraPath, s: Surface, bsdf: Bsdf) -> vec3<f32> {
    if (s.light < 0) {
        return vec3<f32>(0.0);
    }
    let le = area_light_radiance(u32(s.light), path.direction);
    if (le.w <= 0.0) {
        return vec3<f32>(0.0);
    }
    var w = 1.0;
    if (path.last_specular == 0u) {
#if MEDIA
        let light_pdf = le.w * (path.gap + path.hit.t) * (path.gap + path.hit.t) / abs(bsdf.fix.z);
#else
        let light_pdf = le.w * path.hit.t * path.hit.t / abs(bsdf.fix.z);
#endif
        w = mis_weight(path.last_pdf, light_pdf * light_pmf(u32(s.light)));
    }
    return path.throughput * w * le.xyz;
}
