// Bidirectional path tracing with both sub-paths of a sample in one thread (NaiveBPT): the
// item carries the camera sub-path and the stored vertices of its own light sub-path. A
// connection joins a light vertex to a camera vertex with at least one camera segment, so a
// stored vertex is at most MAX_PATH_LENGTH - 2 segments from the light: that many slots hold
// every vertex a path of MAX_PATH_LENGTH segments can use (the graph's `shadow` stream
// declares one more emit per call, the light sample).

const LIGHT_VERTEX_SLOTS: u32 = max(MAX_PATH_LENGTH, 3u) - 2u;

struct BptPath {
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
    light_count: u32,           // stored light vertices
    pad: u32,
    light: array<LightVertex, LIGHT_VERTEX_SLOTS>,
}

// What the strategies at a camera vertex need of the camera sub-path (NaiveBPT and LVC-BPT).
struct CameraVertex {
    throughput: vec3<f32>,
    pixel: u32,
    d_vcm: f32,
    d_vc: f32,
    length: u32,                // camera segments traced so far
}

fn bpt_camera_vertex(p: BptPath) -> CameraVertex {
    return CameraVertex(p.throughput, p.pixel, p.d_vcm, p.d_vc, p.length);
}

// Where a camera sub-path's last ray arrived: the surface and its BSDF, the MIS quantities
// updated for the segment, and whether the path can go on from there.
struct CameraArrival {
    s: Surface,
    bsdf: Bsdf,
    d_vcm: f32,
    d_vc: f32,
    alive: bool,
}

// The camera sub-path of vertex `v` traced `direction` from `origin` and found `hit` (t < 0:
// it escaped). Adds the emission found there (s = 0: the background or an area light),
// MIS-weighted with connections counting `eta` (1 for NaiveBPT, LVC-BPT's ratio otherwise),
// to the film; returns the surface with the MIS quantities updated for the segment.
fn camera_arrive(v: CameraVertex, origin: vec3<f32>, direction: vec3<f32>, hit: Hit, eta: f32) -> CameraArrival {
    var a: CameraArrival;
    a.alive = false;
    if (hit.t < 0.0) {
        let bg = background_radiance(direction);
        if (bg.w > 0.0) {
            let pmf = light_pmf(u32(scene.background));
            let w = bpt_hit_weight(v, bg.w * pmf, bg.w * disk_pdf(scene.radius) * pmf, eta);
            film_add(v.pixel, v.throughput * w * bg.xyz);
        }
        return a;
    }
    a.s = surface_at(hit, origin, direction);
    a.bsdf = bsdf_setup(material_at(a.s.material, a.s.tex), a.s.normal, -direction);
    if (!a.bsdf.valid) {
        return a;
    }
    let c = mis_pow(abs(a.bsdf.fix.z));
    var u = v;
    u.d_vcm = mis_clamp(v.d_vcm * mis_pow(hit.t * hit.t) / c);
    u.d_vc = mis_clamp(v.d_vc / c);
    a.d_vcm = u.d_vcm;
    a.d_vc = u.d_vc;
    if (a.s.light >= 0) {
        let le = area_light_radiance(u32(a.s.light), direction);
        if (le.w > 0.0) {
            let pmf = light_pmf(u32(a.s.light));
            let cos_light = dot(lights[u32(a.s.light)].normal, -direction);
            let w = bpt_hit_weight(u, le.w * pmf, le.w * cos_light * INV_PI * pmf, eta);
            film_add(v.pixel, v.throughput * w * le.xyz);
        }
    }
    a.alive = true;
    return a;
}

// The camera ray of sample `index` (pixel index % PIXELS, jittered) with its MIS quantity.
fn bpt_camera_start(p: ptr<function, BptPath>, index: u32, rng: ptr<function, u32>) {
    let pixel = index % PIXELS;
    let jitter = rng_vec2(rng);
    let direction = camera_direction(f32(pixel % WIDTH) + jitter.x, f32(pixel / WIDTH) + jitter.y);
    (*p).origin = camera.position;
    (*p).direction = direction;
    (*p).pixel = pixel;
    (*p).length = 0u;
    (*p).throughput = vec3<f32>(1.0);
    let camera_pdf = camera_pdf_w(dot(direction, camera.forward));
    (*p).d_vcm = mis_clamp(mis_pow(f32(PIXELS) / camera_pdf));
    (*p).d_vc = 0.0;
}

// MIS weight of the s = 0 strategy (the camera sub-path hits a light) with emission
// densities (area or solid angle `direct_pdf`, `emission_pdf`) already including the pick.
// `eta` is how many times a vertex connection (s >= 2, t >= 2) is sampled per camera
// vertex relative to the other strategies (1 in NaiveBPT; see `scatter`): the light vertex
// here was reached by a camera scatter, whose d_vcm counts eta, but the strategy that picks
// the light point directly (s = 1) counts once.
fn bpt_hit_weight(p: CameraVertex, direct_pdf: f32, emission_pdf: f32, eta: f32) -> f32 {
    if (p.length == 1u) {
        return 1.0;
    }
    let w_camera = mis_pow(direct_pdf) * p.d_vcm / mis_pow(eta) + mis_pow(emission_pdf) * p.d_vc;
    return 1.0 / (1.0 + w_camera);
}

// The s = 1 strategy: a shadow ray towards a light sampled from the camera vertex; a zero
// contribution when there is none.
fn bpt_direct(p: CameraVertex, s: Surface, bsdf: Bsdf, u: f32, uv: vec2<f32>) -> ShadowRay {
    var ray = ShadowRay(s.position, p.pixel, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0));
    let pick = pick_light(u);
    let ill = illuminate(pick.index, s.position, uv);
    if (is_black(ill.radiance)) {
        return ray;
    }
    let e = bsdf_eval(bsdf, ill.direction);
    if (is_black(e.f)) {
        return ray;
    }
    let emission = emission_pdf_of(pick.index, ill);
    let q = bsdf.continuation;
    let forward = select(e.pdf_forward * q, 0.0, ill.is_delta);
    let w_light = mis_pow(forward / (pick.probability * ill.pdf));
    let w_camera = mis_pow(emission.x * e.cos_gen / (ill.pdf * emission.y)) * (p.d_vcm + p.d_vc * mis_pow(e.pdf_reverse * q));
    let w = 1.0 / (w_light + 1.0 + w_camera);
    ray.contribution = p.throughput * ill.radiance * e.f * (w * e.cos_gen / (pick.probability * ill.pdf));
    ray.origin = offset_ray_origin(s.position, side_normal(s.normal, ill.direction), s.extent);
    ray.direction = ill.direction;
    ray.distance = light_shadow_distance(s.position, ray.origin, ill);
    return ray;
}

// The s >= 2 strategies: connects the camera vertex to a stored light vertex; the strategy
// counts `eta` times against the others (see `bpt_hit_weight`).
fn bpt_connect(p: CameraVertex, s: Surface, bsdf: Bsdf, v: LightVertex, eta: f32) -> ShadowRay {
    var ray = ShadowRay(s.position, p.pixel, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0));
    let to_light = v.position - s.position;
    let distance2 = dot(to_light, to_light);
    if (!(distance2 > 0.0)) {
        return ray;
    }
    let direction = to_light * inverseSqrt(distance2);
    let ec = bsdf_eval(bsdf, direction);
    if (is_black(ec.f)) {
        return ray;
    }
    let lb = light_vertex_bsdf(v);
    if (!lb.valid) {
        return ray;
    }
    let el = bsdf_eval(lb, -direction);
    if (is_black(el.f)) {
        return ray;
    }
    let qc = bsdf.continuation;
    let ql = lb.continuation;
    let camera_pdf_a = ec.pdf_forward * qc * el.cos_gen / distance2;
    let light_pdf_a = el.pdf_forward * ql * ec.cos_gen / distance2;
    let w_light = mis_pow(camera_pdf_a) * (v.d_vcm + v.d_vc * mis_pow(el.pdf_reverse * ql));
    let w_camera = mis_pow(light_pdf_a) * (p.d_vcm + p.d_vc * mis_pow(ec.pdf_reverse * qc));
    let w = 1.0 / ((w_light + w_camera) / mis_pow(eta) + 1.0);
    ray.contribution = p.throughput * v.throughput * ec.f * el.f * (w * ec.cos_gen * el.cos_gen / distance2);
    ray.origin = offset_ray_origin(s.position, side_normal(s.normal, direction), s.extent);
    ray.direction = direction;
    ray.distance = shadow_distance(ray.origin, v.position);
    return ray;
}
