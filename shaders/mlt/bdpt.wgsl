// Multiplexed MLT's paths (Hachisuka, Kaplanyan and Dachsbacher 2014): the primary samples
// pick a path length k (uniformly in 1..MAX_PATH_LENGTH) and one of its bidirectional
// techniques, s light vertices and t = k + 1 - s camera vertices (uniformly among the k + 1
// techniques; the camera sees no light by light tracing, so k = 1 has s = 0 alone), then
// trace only that technique's sub-paths and connection, with BPT's own functions and MIS
// weights (shaders/lt/subpath.wgsl, shaders/bpt/path.wgsl; the weights of all techniques of a
// path add up to 1, as in NaiveBPT). The contribution is divided by the technique's
// probability, so the evaluator's mean over uniform samples is NaiveBPT's estimate of the
// image. The camera sub-path draws from stream 0 (whose first two numbers pick the
// technique), the light sub-path from stream 1 (shaders/mlt/streams.wgsl).

// The techniques of paths of `k` segments: s = 0..k, except s = k = 1 (t = 1 connects only
// vertices past the light's own).
fn mmlt_techniques(k: u32) -> u32 {
    return select(k + 1u, 1u, k == 1u);
}

// Hook: a Markov chain's path evaluator, the path the primary samples of `src` make (its
// pixel and contribution; the chain's target is its luminance). Default here: one
// bidirectional technique picked by the samples (mmlt).
fn mlt_path(src: ptr<function, PrimarySamples>) -> MltPath {
    streams_read(*src);
    var camera_rng = stream_start(0u);
    var light_rng = stream_start(1u);
    let k = 1u + min(u32(rng_f32(&camera_rng) * f32(MAX_PATH_LENGTH)), MAX_PATH_LENGTH - 1u);
    let n = mmlt_techniques(k);
    let s = min(u32(rng_f32(&camera_rng) * f32(n)), n - 1u);
    var c = camera_subpath_at_raster(&camera_rng);
    var r: MltPath;
    if (s == k) {
        r = mmlt_light_tracing(k, &camera_rng, &light_rng);
    } else {
        r = mlt_path_of(mmlt_camera_technique(&c, k, s, &camera_rng, &light_rng), vec3<f32>(0.0), c.pixel);
    }
    r.radiance *= f32(MAX_PATH_LENGTH) * f32(n);
    return r;
}

// Techniques with t >= 2 camera vertices: the camera sub-path to its vertex t, then the
// emission it finds there (s = 0), a light sampled from there (s = 1) or a connection to the
// light sub-path's vertex s (s >= 2).
fn mmlt_camera_technique(c: ptr<function, CameraSubpath>, k: u32, s: u32, camera_rng: ptr<function, u32>, light_rng: ptr<function, u32>) -> vec3<f32> {
    let counts = mis_counts(1.0);
    let t = k + 1u - s;
    var landing: CameraLanding;
    for (var i = 1u; i < t; i += 1u) {
        camera_subpath_trace(c);
        landing = camera_land(c, counts);
        if (i + 1u < t && !(landing.a.alive && camera_scatter(c, landing.a, counts, camera_rng))) {
            return vec3<f32>(0.0);
        }
    }
    if (s == 0u) {
        return landing.emission;
    }
    if (!landing.a.alive || landing.a.bsdf.is_delta) {
        return vec3<f32>(0.0);
    }
    if (s == 1u) {
        if (scene.num_lights == 0u) {
            return vec3<f32>(0.0);
        }
        let u = rng_f32(light_rng);
        let ray = bpt_direct(*c, landing.a.s, landing.a.bsdf, u, rng_vec2(light_rng), counts);
        return mlt_unblocked(ray);
    }
    var lp: LightPath;
    if (!mmlt_light_subpath(&lp, s - 1u, light_rng)) {
        return vec3<f32>(0.0);
    }
    let la = light_path_land(&lp);
    if (!la.alive || la.bsdf.is_delta) {
        return vec3<f32>(0.0);
    }
    let ray = bpt_connect(*c, landing.a.s, landing.a.bsdf, light_vertex_at(lp, la.s), counts);
    return mlt_unblocked(ray);
}

// Traces a light sub-path of `segments` segments (its last ray traced, not landed yet);
// false where it ends sooner.
fn mmlt_light_subpath(lp: ptr<function, LightPath>, segments: u32, rng: ptr<function, u32>) -> bool {
    if (scene.num_lights == 0u || !light_path_start_stratified(lp, rng, LightStratum(0u, 1u, 0u))) {
        return false;
    }
    (*lp).rng = *rng;
    for (var j = 1u; j <= segments; j += 1u) {
        light_path_trace(lp);
        if (j == segments) {
            break;
        }
        let a = light_path_land(lp);
        if (!a.alive || !light_path_scatter(lp, a.s, a.bsdf, mis_counts(1.0))) {
            return false;
        }
    }
    *rng = (*lp).rng;
    return true;
}

// The technique t = 1 (s = k): the light sub-path's vertex k - 1 segments from the light,
// connected to the camera; it lands at the pixel it projects to.
fn mmlt_light_tracing(k: u32, camera_rng: ptr<function, u32>, light_rng: ptr<function, u32>) -> MltPath {
    let none = mlt_path_of(vec3<f32>(0.0), vec3<f32>(0.0), 0u);
    var lp: LightPath;
    if (!mmlt_light_subpath(&lp, k - 1u, light_rng)) {
        return none;
    }
    let la = light_path_land(&lp);
    if (!la.alive || la.bsdf.is_delta) {
        return none;
    }
    let lens = camera_lens_sample(camera_rng);
    let ray = light_vertex_to_camera(light_vertex_at(lp, la.s), la.bsdf, mis_counts(1.0), lens);
    return mlt_path_of(mlt_unblocked(ray), vec3<f32>(0.0), ray.pixel);
}
