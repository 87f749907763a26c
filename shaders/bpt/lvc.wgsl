// Light Vertex Cache BPT (Davidovic et al. 2014): phase 1 traces PATHS light sub-paths,
// splats t = 1 and stores every vertex a connection can use in one global cache; phase 2
// traces camera sub-paths, each non-delta vertex connecting to LVC_CONNECTIONS cache
// vertices picked uniformly. A cache of M vertices from PATHS light sub-paths, sampled
// n times, estimates one light sub-path's connections with weight M / (n PATHS); in the MIS
// the connections count n / LVC_AVERAGE_LENGTH (the measured M / PATHS) against the other
// strategies. With LVC_MEASURING the light phase only counts the vertices it would store.

// Connections per camera vertex: ceil of the measured average (at least 1).
fn lvc_connections() -> u32 {
    return max(u32(ceil(LVC_AVERAGE_LENGTH)), 1u);
}

// The count of the connection strategies in the MIS (see `scatter`).
fn lvc_eta() -> f32 {
    return f32(lvc_connections()) / max(LVC_AVERAGE_LENGTH, 1e-3);
}

// An item for passes that only run once per frame.
struct LvcOnce {
    pad: u32,
}

// Pass `lvc_reset` (Start over 1): empties the cache before the light phase.
fn lvc_reset(item: ptr<function, LvcOnce>, index: u32) -> bool {
    atomicStore(&lvc_count, 0u);
    return false;
}

// Pass `lvc_light_generate` (Start over the light sub-paths): counts the sub-path for the
// measured average, then starts it as light tracing does.
fn lvc_light_generate(p: ptr<function, LightPath>, index: u32) -> bool {
    count(COUNTER_LVC_PATHS, 1u);
    return light_generate(p, index);
}

// Pass `lvc_bounce` (Loop): at the light sub-path's new vertex, the t = 1 splat, the vertex
// into the cache (counted as overflow when the cache is full), and the next direction.
fn lvc_bounce(p: ptr<function, LightPath>) -> bool {
    if ((*p).hit_t < 0.0) {
        return false;
    }
    let s = light_path_surface(*p);
    let bsdf = light_path_bsdf(*p, s);
    if (!bsdf.valid) {
        return false;
    }
    light_path_arrive(p, bsdf);
    if (!bsdf.is_delta) {
        let v = light_vertex_at(*p, s);
        if ((*p).length + 2u <= MAX_PATH_LENGTH) {
            count(COUNTER_LVC_STORED, 1u);
            if (!LVC_MEASURING) {
                let i = atomicAdd(&lvc_count, 1u);
                if (i < arrayLength(&lvc_cache)) {
                    lvc_cache[i] = v;
                } else {
                    count(COUNTER_LVC_OVERFLOW, 1u);
                }
            }
        }
        if (!LVC_MEASURING && (*p).length + 1u <= MAX_PATH_LENGTH) {
            let ray = light_vertex_to_camera(v, bsdf);
            if (!is_black(ray.contribution)) {
                emit_splat(ray);
            }
        }
    }
    if ((*p).length + 2u > MAX_PATH_LENGTH) {
        return false;
    }
    return light_path_scatter(p, s, bsdf, lvc_eta());
}

// A camera sub-path of LVC-BPT between passes.
struct LvcPath {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
    length: u32,                // camera segments traced so far
    throughput: vec3<f32>,
    rng: u32,
    d_vcm: f32,
    d_vc: f32,
    hit_t: f32,                 // negative: the last ray escaped
    hit_primitive: u32,
    hit_uv: vec2<f32>,
}

// Pass `lvc_camera` (Start over PATHS): the camera ray of sample `index`; none while
// measuring.
fn lvc_camera(p: ptr<function, LvcPath>, index: u32) -> bool {
    if (LVC_MEASURING) {
        return false;
    }
    var rng = rng_seed(frame.seed ^ 0x9e3779b9u, frame.index, index);
    let pixel = index % PIXELS;
    let jitter = rng_vec2(&rng);
    let direction = camera_direction(f32(pixel % WIDTH) + jitter.x, f32(pixel / WIDTH) + jitter.y);
    *p = LvcPath(camera.position, pixel, direction, 0u, vec3<f32>(1.0), rng,
        mis_clamp(mis_pow(f32(PIXELS) / camera_pdf_w(dot(direction, camera.forward)))), 0.0, 0.0, 0u, vec2<f32>(0.0));
    return true;
}

// Pass `lvc_trace` (Loop): finds the closest hit of the camera sub-path's ray.
fn lvc_trace(p: ptr<function, LvcPath>) -> bool {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*p).length == 0u), 1u);
    let hit = trace_closest((*p).origin, (*p).direction, INFINITE_DISTANCE);
    (*p).hit_t = select(-1.0, hit.t, hit.found);
    (*p).hit_primitive = hit.primitive;
    (*p).hit_uv = hit.uv;
    (*p).length += 1u;
    return true;
}

fn lvc_camera_vertex(p: LvcPath) -> CameraVertex {
    return CameraVertex(p.throughput, p.pixel, p.d_vcm, p.d_vc, p.length);
}

// Pass `lvc_vertex` (Loop): at the camera sub-path's new vertex, emission found (s = 0), a
// light sampled directly (s = 1) and LVC_CONNECTIONS connections to cache vertices (s >= 2),
// each MIS-weighted; then the next direction.
fn lvc_vertex(p: ptr<function, LvcPath>) -> bool {
    let eta = lvc_eta();
    let a = camera_arrive(lvc_camera_vertex(*p), (*p).origin, (*p).direction, Hit((*p).hit_t, (*p).hit_primitive, (*p).hit_uv, true), eta);
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
        let camera_vertex = lvc_camera_vertex(*p);
        if (scene.num_lights > 0u) {
            let ray = bpt_direct(camera_vertex, s, bsdf, light_u, light_uv);
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
        let m = min(atomicLoad(&lvc_count), arrayLength(&lvc_cache));
        let n = lvc_connections();
        let scale = f32(m) / (f32(n) * f32(PATHS));
        for (var k = 0u; k < n; k += 1u) {
            let u = rng_f32(&rng);
            if (m == 0u) {
                continue;
            }
            let v = lvc_cache[min(u32(u * f32(m)), m - 1u)];
            if (light_vertex_length(v) + 1u + (*p).length > MAX_PATH_LENGTH) {
                continue;
            }
            var ray = bpt_connect(camera_vertex, s, bsdf, v, eta);
            ray.contribution *= scale;
            if (!is_black(ray.contribution)) {
                emit_shadow(ray);
            }
        }
    }
    let r = scatter(bsdf, s, (*p).throughput, (*p).d_vcm, (*p).d_vc, eta, &rng);
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
