// Bidirectional path tracing with both sub-paths of a sample in one thread (NaiveBPT): the
// item carries the camera sub-path and the stored vertices of its own light sub-path. A
// connection joins a light vertex to a camera vertex with at least one camera segment, so a
// stored vertex is at most MAX_PATH_LENGTH - 2 segments from the light: that many slots hold
// every vertex a path of MAX_PATH_LENGTH segments can use (the graph's `shadow` stream
// declares one more emit per call, the light sample).

const LIGHT_VERTEX_SLOTS: u32 = max(MAX_PATH_LENGTH, 3u) - 2u;

// A camera sub-path between passes: LVC-BPT's item, and the camera half of NaiveBPT's.
struct CameraSubpath {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
    length: u32,                // camera segments traced so far
    throughput: vec3<f32>,
    rng: u32,
    d_vcm: f32,
    d_vc: f32,
    hit: PathHit,               // the last traced ray's hit (t < 0: it escaped)
}

// NaiveBPT's item: a camera sub-path and the stored vertices of its sample's light sub-path.
struct BptPath {
    camera: CameraSubpath,
    light_count: u32,           // stored light vertices
    pad: u32,
    light: array<LightVertex, LIGHT_VERTEX_SLOTS>,
}

// A camera ray through `pixel` with its MIS quantity; `rng` goes on in the sub-path. Sample
// `index` takes pixel index % PIXELS in NaiveBPT and StreamingBPT, and that pixel in tile
// order in LVC-BPT and VCM (as in photon mapping, so that a workgroup's vertices are close).
fn camera_subpath_start(pixel: u32, rng: ptr<function, u32>) -> CameraSubpath {
    return camera_subpath_along(camera_jittered_ray(pixel, rng), pixel, *rng);
}

// A camera sub-path along `ray`, a ray through `pixel`, that goes on with the random stream `rng`.
fn camera_subpath_along(ray: CameraRay, pixel: u32, rng: u32) -> CameraSubpath {
    let d_vcm = mis_clamp(mis_pow(f32(PIXELS) / camera_pdf_w(dot(ray.direction, camera.forward))));
    return CameraSubpath(ray.origin, pixel, ray.direction, 0u, vec3<f32>(1.0), rng, d_vcm, 0.0, PathHit());
}

// A camera sub-path through a raster position drawn as two continuous numbers of `rng`, then
// its lens sample (a Markov chain's camera stream: a small step of the numbers moves the ray a
// little, where a pixel index would jump along the row); `rng` goes on in the sub-path.
fn camera_subpath_at_raster(rng: ptr<function, u32>) -> CameraSubpath {
    let x = rng_f32(rng) * f32(WIDTH);
    let y = rng_f32(rng) * f32(HEIGHT);
    let lens = camera_lens_sample(rng);
    let pixel = min(u32(y), HEIGHT - 1u) * WIDTH + min(u32(x), WIDTH - 1u);
    return camera_subpath_along(camera_ray(x, y, lens), pixel, *rng);
}

// The trace passes of camera sub-paths: the closest hit of the sub-path's ray.
fn camera_subpath_trace(c: ptr<function, CameraSubpath>) {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*c).length == 0u), 1u);
    let hit = trace_closest((*c).origin, (*c).direction, INFINITE_DISTANCE);
    (*c).hit = path_hit(hit);
    (*c).length += 1u;
}

// Camera sub-path `c` arrives where its last ray went (hit.t < 0: it escaped). Adds the
// emission found there (s = 0: the background or an area light), MIS-weighted with the
// strategies counted as `counts`, to the film, and at a surface brings the MIS quantities
// to the new vertex.
fn camera_arrive(c: ptr<function, CameraSubpath>, counts: MisCounts) -> Arrival {
    let found = camera_land(c, counts);
    if (!is_black(found.emission)) {
        film_add((*c).pixel, found.emission);
    }
    return found.a;
}

// Where a camera sub-path arrived (`camera_land`), and the MIS-weighted emission it found there
// (s = 0).
struct CameraLanding {
    a: Arrival,
    emission: vec3<f32>,
}

// `camera_arrive` without the film: the arrival and the emission found, for the caller to add.
fn camera_land(c: ptr<function, CameraSubpath>, counts: MisCounts) -> CameraLanding {
    var r: CameraLanding;
    r.a.alive = false;
    r.emission = vec3<f32>(0.0);
    let direction = (*c).direction;
    if (path_hit_escaped((*c).hit)) {
        let bg = background_radiance(direction);
        if (bg.w > 0.0) {
            let pmf = light_pmf(u32(scene.background));
            let w = bpt_hit_weight(*c, bg.w * pmf, bg.w * disk_pdf(scene.radius) * pmf, counts);
            r.emission = (*c).throughput * w * bg.xyz;
        }
        return r;
    }
    let t = (*c).hit.t;
    r.a.s = path_hit_surface((*c).hit, (*c).origin, direction);
    r.a.bsdf = surface_bsdf(r.a.s, -direction);
    if (!r.a.bsdf.valid) {
        return r;
    }
    let cos_fix = mis_pow(abs(r.a.bsdf.fix.z));
    (*c).d_vcm = mis_clamp((*c).d_vcm * mis_pow(t * t) / cos_fix);
    (*c).d_vc = mis_clamp((*c).d_vc / cos_fix);
    if (r.a.s.light >= 0) {
        let le = area_light_radiance(u32(r.a.s.light), direction);
        if (le.w > 0.0) {
            let pmf = light_pmf(u32(r.a.s.light));
            let cos_light = dot(lights[u32(r.a.s.light)].normal, -direction);
            let w = bpt_hit_weight(*c, le.w * pmf, le.w * cos_light * INV_PI * pmf, counts);
            r.emission = (*c).throughput * w * le.xyz;
        }
    }
    r.a.alive = true;
    return r;
}

// What a camera sub-path found at the vertex it arrived at (`camera_visit`).
struct CameraVisit {
    a: Arrival,
    alive: bool,                // false: the sub-path ends here
    rng: u32,                   // random numbers for the connections and the scatter
    direct: ShadowRay,          // the s = 1 shadow ray; a black contribution: none
}

// Camera sub-path `c` arrives at its next vertex (`camera_arrive`, strategies counted as
// `counts`) and, at a non-delta vertex, samples a light (s = 1): the shadow ray, which the
// caller emits. LVC-BPT, VCM and NaiveBPT emit it with their connections, at one place
// (`lvc_shadow_rays`, `bpt_vertex`), so that a fused `shadow` inlines one any-hit traversal
// (docs/performance.md, "The CWBVH's child loop"); StreamingBPT at once
// (`camera_emit_direct`).
// The light's random numbers are drawn even where unused, so every estimator built on this
// consumes the same numbers per vertex; none without light sampling (`counts.vc` false:
// photon mapping's numbers).
fn camera_visit(c: ptr<function, CameraSubpath>, counts: MisCounts) -> CameraVisit {
    return camera_visit_at(c, camera_arrive(c, counts), counts);
}

// `camera_visit` at arrival `a` of camera sub-path `c`, the emission found there taken care of
// (`camera_arrive` adds it to the film; a chain's evaluator adds it to its path, `camera_land`).
fn camera_visit_at(c: ptr<function, CameraSubpath>, a: Arrival, counts: MisCounts) -> CameraVisit {
    var v: CameraVisit;
    v.a = a;
    v.alive = false;
    if (!v.a.alive) {
        return v;
    }
    var rng = (*c).rng;
    var light_u = 0.0;
    var light_uv = vec2<f32>(0.0);
    if (counts.vc) {
        light_u = rng_f32(&rng);
        light_uv = rng_vec2(&rng);
    }
    v.rng = rng;
    if ((*c).length >= MAX_PATH_LENGTH) {
        return v;
    }
    if (counts.vc && !v.a.bsdf.is_delta && scene.num_lights > 0u) {
        v.direct = bpt_direct(*c, v.a.s, v.a.bsdf, light_u, light_uv, counts);
    }
    v.alive = true;
    return v;
}

// Continues camera sub-path `c` from where it arrived (strategies counted as `counts`, see
// `scatter`); false when it ends.
fn camera_scatter(c: ptr<function, CameraSubpath>, a: Arrival, counts: MisCounts, rng: ptr<function, u32>) -> bool {
    let r = scatter(a.bsdf, a.s, (*c).throughput, (*c).d_vcm, (*c).d_vc, counts, rng);
    if (!r.alive) {
        return false;
    }
    (*c).origin = r.origin;
    (*c).direction = r.direction;
    (*c).throughput = r.throughput;
    (*c).d_vcm = r.d_vcm;
    (*c).d_vc = r.d_vc;
    return true;
}

// MIS weight of the s = 0 strategy (the camera sub-path hits a light) with emission
// densities (area or solid angle `direct_pdf`, `emission_pdf`) already including the pick.
// The light vertex here was reached by a camera scatter, whose d_vcm counts the vertex
// connections' `counts.connect` (see `scatter`), but the strategy that picks the light point
// directly (s = 1) counts once. Without connections (`counts.vc` false, merging alone) the
// light counts on paths left through delta lobes alone, whose dVM (d_vc) is still 0, and
// merges take every other path.
fn bpt_hit_weight(p: CameraSubpath, direct_pdf: f32, emission_pdf: f32, counts: MisCounts) -> f32 {
    if (!counts.vc) {
        return select(0.0, 1.0, p.d_vc == 0.0);
    }
    if (p.length == 1u) {
        return 1.0;
    }
    let w_camera = mis_pow(direct_pdf) * p.d_vcm / mis_pow(counts.connect) + mis_pow(emission_pdf) * p.d_vc;
    return 1.0 / (1.0 + w_camera);
}

// The s = 1 strategy: a shadow ray towards a light sampled from the camera vertex, weighed
// against the strategies counted as `counts`; a zero contribution when there is none.
fn bpt_direct(p: CameraSubpath, s: Surface, bsdf: Bsdf, u: f32, uv: vec2<f32>, counts: MisCounts) -> ShadowRay {
    let none = ShadowRay();
    let pick = pick_light(u);
    let ill = illuminate(pick.index, s.position, uv);
    if (is_black(ill.radiance)) {
        return none;
    }
    let e = bsdf_eval(bsdf, ill.direction);
    if (is_black(e.f)) {
        return none;
    }
    let emission = emission_pdf_of(pick.index, ill);
    let q = bsdf.continuation;
    let forward = select(e.pdf_forward * q, 0.0, ill.is_delta);
    let w_light = mis_pow(forward / (pick.probability * ill.pdf));
    let w_camera = mis_pow(emission.x * e.cos_gen / (ill.pdf * emission.y)) * (counts.merge + p.d_vcm + p.d_vc * mis_pow(e.pdf_reverse * q));
    let w = 1.0 / (w_light + 1.0 + w_camera);
    return light_sample_ray(s, ill, p.pixel, p.throughput * ill.radiance * e.f * (w * e.cos_gen / (pick.probability * ill.pdf)));
}

// The s >= 2 strategies: connects the camera vertex to a stored light vertex; the strategy
// counts `counts.connect` times against the others (see `bpt_hit_weight`), a merge at
// either end `counts.merge` times.
fn bpt_connect(p: CameraSubpath, s: Surface, bsdf: Bsdf, v: LightVertex, counts: MisCounts) -> ShadowRay {
#if MEDIA
    var ray = ShadowRay(s.position, p.pixel, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), VACUUM);
#else
    var ray = ShadowRay(s.position, p.pixel, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0));
#endif
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
    let w_light = mis_pow(camera_pdf_a) * (counts.merge + v.d_vcm + v.d_vc * mis_pow(el.pdf_reverse * ql));
    let w_camera = mis_pow(light_pdf_a) * (counts.merge + p.d_vcm + p.d_vc * mis_pow(ec.pdf_reverse * qc));
    let w = 1.0 / ((w_light + w_camera) / mis_pow(counts.connect) + 1.0);
    ray.contribution = p.throughput * v.throughput * ec.f * el.f * (w * ec.cos_gen * el.cos_gen / distance2);
    ray.origin = offset_ray_origin(s.position, side_normal(s.normal, direction), s.extent);
    ray.direction = direction;
    ray.distance = shadow_distance(ray.origin, v.position);
    return ray;
}

// A camera sub-path vertex StreamingBPT keeps for its connection stage: what `bpt_connect`
// needs of the sub-path, the surface and the BSDF there. Declared with the catalog's library
// since the catalog's `sbpt_camera_vertices` holds it (graphs that include the catalog whole,
// such as vcm, declare that buffer too).
struct CameraVertex {
    position: vec3<f32>,
    extent: f32,
    throughput: vec3<f32>,
    d_vcm: f32,
    normals: VertexNormals,
    d_vc: f32,
    towards: vec3<f32>,         // towards the previous vertex
    material: u32,
    tex: vec2<f32>,
    pixel: u32,
    length: u32,
}
