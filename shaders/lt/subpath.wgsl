// Light sub-paths and the recursive MIS of bidirectional path tracing (Georgiev et al. 2012,
// "Implementing vertex connection and merging", in the dVCM / dVC form; balance heuristic,
// or the power heuristic with MIS_POWER). dVM is not carried: with connections and merging
// (VCM) it is dVC / mis_pow(pi r^2 N_light) all along (the same recursion, Georgiev et al.'s
// light and camera starts), and with merging alone d_vc carries it (see `MisCounts`). The
// quantities are kept below MIS_LIMIT so that long glossy chains cannot overflow them into
// infinities and NaNs; a weight whose sum overflows anyway is 1 / (1 + inf) = 0.
//
// Path lengths count segments. Light sub-paths start on a light picked by `pick_light`;
// LIGHT_PATHS_PER_FRAME = PIXELS light sub-paths stand against one camera sample per pixel
// (SmallVCM's light sub-path count), so a camera connection is divided by PIXELS.
// Needs the constant LIGHT_TRACE_ONLY (true: the t = 1 strategy alone, weight 1).

const MIS_LIMIT: f32 = 1e30;

// How often each kind of strategy is sampled in the MIS (the balance heuristic over n_i p_i),
// in units of a vertex connection sampled once per camera vertex, as Georgiev et al. count
// them: `connect`, the vertex connections (s, t >= 2) per camera vertex (1 in NaiveBPT,
// LVC-BPT's ratio `lvc_eta`); `merge`, mis_pow of a merge's count pi r^2 N_light (0 without
// merging, VCM); `vc`, whether light sampling, light tracing and connections run at all (false:
// VCM as PBPM, merging alone, where d_vc carries dVM and emission counts only on paths that
// were left through delta lobes alone). The light sampling, light tracing and the emission a
// camera sub-path hits count once.
struct MisCounts {
    connect: f32,
    merge: f32,
    vc: bool,
}

// The counts of bidirectional path tracing without merging, connections counting `connect`.
fn mis_counts(connect: f32) -> MisCounts {
    return MisCounts(connect, 0.0, true);
}

// MIS exponent applied to a density ratio.
fn mis_pow(x: f32) -> f32 {
    return select(x, x * x, MIS_POWER);
}

// Keeps a recursive MIS quantity finite.
fn mis_clamp(x: f32) -> f32 {
    return min(x, MIS_LIMIT);
}

// A light sub-path between passes: the ray to trace next, the hit found for it, and the MIS
// quantities of its last vertex.
struct LightPath {
    origin: vec3<f32>,
    length: u32,            // segments traced so far
    direction: vec3<f32>,
    rng: u32,
    throughput: vec3<f32>,
    d_vcm: f32,
    d_vc: f32,
    is_finite: u32,         // 0: the light is at infinity (directional, background)
    hit: PathHit,           // the last traced ray's hit (t < 0: it escaped)
    index: u32,             // the sub-path's index in the frame
#if MEDIA
    medium: i32,            // the medium the ray travels in (-1: vacuum; shaders/lt/media.wgsl)
    vertex: u32,            // what the ray found: VERTEX_SURFACE at the hit, or VERTEX_MEDIUM at hit.t in `medium`
#endif
}

// A stored light sub-path vertex (48 bytes; 64 with shading normals): position moved off the
// surface to the side the sub-path arrived from (the only side a connection can reach),
// throughput, MIS quantities, the normals (the shading one only in scenes with vertex
// normals: PackedNormals) and the direction towards the previous vertex octahedrally packed,
// material index (24 bits) with the sub-path length (8 bits), and the texture coordinates
// wrapped to [0, 1) in 16 bits each (repeating textures look the same).
struct LightVertex {
    position: vec3<f32>,
    d_vcm: f32,
    throughput: vec3<f32>,
    d_vc: f32,
    normals: PackedNormals,
    fix: u32,
    material_length: u32,
    tex: u32,
}

// Which stratum of the light a sub-path starts in: sub-path `index` of the `count` of frame
// `frame_index` (that frame's random numbers: with FRAMES_AT_ONCE, its frame slot's).
struct LightStratum {
    index: u32,
    count: u32,
    frame_index: u32,
}

// Starts a light sub-path with the path's random numbers in stratum `stratum`; false when the
// emission is void. The point on the light (the disc of a distant light) is stratified along
// a Z curve over the unit square, rotated by one random shift a frame, so that neighbouring
// sub-paths start close together and each sub-path's point is still uniform
// (`light_stratified_point`); with LIGHT_STRATA false, each draws its own point.
fn light_path_start_stratified(p: ptr<function, LightPath>, rng: ptr<function, u32>, stratum: LightStratum) -> bool {
    let pick = pick_light(rng_f32(rng));
    var u_point = rng_vec2(rng);
    if (LIGHT_STRATA) {
        u_point = light_stratified_point(stratum, u_point.x, rng_vec2(rng));
    }
    let u_direction = rng_vec2(rng);
    let e = emit_light(pick.index, u_point, u_direction);
    if (is_black(e.radiance)) {
        return false;
    }
    let emission_pdf = e.emission_pdf * pick.probability;
    let direct_pdf = e.direct_pdf * pick.probability;
    (*p).origin = e.origin;
    (*p).direction = e.direction;
    (*p).length = 0u;
    (*p).throughput = e.radiance * (e.cos_light / emission_pdf);
    (*p).d_vcm = mis_clamp(mis_pow(direct_pdf / emission_pdf));
    (*p).d_vc = 0.0;
    if (!e.is_delta) {
        (*p).d_vc = mis_clamp(mis_pow(e.cos_light / emission_pdf));
    }
    (*p).is_finite = select(0u, 1u, e.is_finite);
#if MEDIA
    return light_path_start_in_media(p);
#else
    return true;
#endif
}

// Whether a sub-path `light_path_start_stratified` started left a delta light: its d_vc is 0
// then, and only then for a start that carries light (a light with an area or a direction to
// sample gives cos / pdf > 0; a start whose cosine is 0 carries none). Valid until the first
// `scatter`, which photon mapping's sub-paths never call (they keep d_vc as it started).
fn light_path_from_delta_light(p: LightPath) -> bool {
    return p.d_vc == 0.0;
}

// A point of the unit square for sub-path `index` of `count` (`stratum`): stratum
// index / count of a Z curve over the square (its position in 32-bit fixed point, `jitter`
// inside the stratum), plus one random shift of its frame (a rotation, so the point is uniform
// whatever the stratum), cut into 16 bits along each axis and jittered in that last cell by
// `cell`.
fn light_stratified_point(stratum: LightStratum, jitter: f32, cell: vec2<f32>) -> vec2<f32> {
    let step = 0xffffffffu / stratum.count;
    let shift = rng_hash(stratum.frame_index ^ rng_hash(frame.seed ^ 0x5bd1e995u));
    let x = stratum.index * step + u32(jitter * f32(step)) + shift;
    let at = vec2<f32>(vec2<u32>(z_curve_compact(x), z_curve_compact(x >> 1u)));
    return (at + cell) * (1.0 / 65536.0);
}

// The even bits of x, packed into the low 16.
fn z_curve_compact(x: u32) -> u32 {
    var v = x & 0x55555555u;
    v = (v | (v >> 1u)) & 0x33333333u;
    v = (v | (v >> 2u)) & 0x0f0f0f0fu;
    v = (v | (v >> 4u)) & 0x00ff00ffu;
    return (v | (v >> 8u)) & 0x0000ffffu;
}

// Traces the sub-path's next ray.
fn light_path_trace(p: ptr<function, LightPath>) {
    count(COUNTER_RAYS_LIGHT, 1u);
    let hit = trace_closest((*p).origin, (*p).direction, INFINITE_DISTANCE);
    (*p).hit = path_hit(hit);
    (*p).length += 1u;
#if MEDIA
    light_path_through_media(p);
#endif
}

// The surface the sub-path's last ray hit.
fn light_path_surface(p: LightPath) -> Surface {
    return path_hit_surface(p.hit, p.origin, p.direction);
}

// The BSDF at the hit, for importance transport.
fn light_path_bsdf(p: LightPath, s: Surface) -> Bsdf {
    var bsdf = surface_bsdf(s, -p.direction);
    bsdf.adjoint = true;
    return bsdf;
}

// Brings the MIS quantities to the new vertex: area densities at the hit (distance squared,
// except after a light at infinity, whose first segment has no finite length; the cosine).
fn light_path_arrive(p: ptr<function, LightPath>, bsdf: Bsdf) {
    let t = (*p).hit.t;
    if ((*p).length > 1u || (*p).is_finite != 0u) {
        (*p).d_vcm = mis_clamp((*p).d_vcm * mis_pow(t * t));
    }
    let c = mis_pow(abs(bsdf.fix.z));
    (*p).d_vcm = mis_clamp((*p).d_vcm / c);
    (*p).d_vc = mis_clamp((*p).d_vc / c);
}

// Where a sub-path's last ray arrived: the surface, its BSDF, and whether the sub-path has a
// vertex there (false when the ray escaped or the BSDF is invalid).
struct Arrival {
    s: Surface,
    bsdf: Bsdf,
    alive: bool,
}

// Light sub-path `p` arrives where its last ray went: its surface and BSDF, with the MIS
// quantities brought there (`light_path_arrive`).
fn light_path_land(p: ptr<function, LightPath>) -> Arrival {
    var a: Arrival;
    a.alive = false;
    if (path_hit_escaped((*p).hit)) {
        return a;
    }
    a.s = light_path_surface(*p);
    a.bsdf = light_path_bsdf(*p, a.s);
    if (!a.bsdf.valid) {
        return a;
    }
    light_path_arrive(p, a.bsdf);
    a.alive = true;
    return a;
}

// Where a light sub-path's vertex at surface `s` is stored (cache vertices and photons
// alike): moved off the surface to the side it arrived from, `towards` its previous vertex.
fn light_vertex_position(s: Surface, towards: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin(s.position, side_normal(s.normal, towards), s.extent);
}

// The vertex to store for a sub-path at surface `s` (after `light_path_arrive`).
fn light_vertex_at(p: LightPath, s: Surface) -> LightVertex {
    let towards = -p.direction;
    var v: LightVertex;
    v.position = light_vertex_position(s, towards);
    v.d_vcm = p.d_vcm;
    v.throughput = p.throughput;
    v.d_vc = p.d_vc;
    v.normals = packed_normals(s);
    v.fix = encode_octahedral(towards);
    v.material_length = min(s.material, 0xffffffu) | (min(p.length, 255u) << 24u);
    v.tex = pack2x16unorm(fract(s.tex));
    return v;
}

// A stored vertex's length (segments from the light).
fn light_vertex_length(v: LightVertex) -> u32 {
    return v.material_length >> 24u;
}

// The BSDF at a stored vertex.
fn light_vertex_bsdf(v: LightVertex) -> Bsdf {
    let m = material_at(v.material_length & 0xffffffu, unpack2x16unorm(v.tex));
    var bsdf = vertex_bsdf(m, unpacked_normals(v.normals), decode_octahedral(v.fix));
    bsdf.adjoint = true;
    return bsdf;
}

// The t = 1 strategy: connects a light vertex to the camera (to the lens point of `lens`,
// `camera_lens_sample`), weighed against the other strategies as `counts` count them. Returns
// the shadow ray towards the camera with the contribution to its pixel; a zero contribution
// when the camera cannot see the vertex. A thin lens's point is picked with density
// 1 / lens area, which cancels the lens area in its importance: the pinhole's formula holds.
fn light_vertex_to_camera(v: LightVertex, bsdf: Bsdf, counts: MisCounts, lens: vec2<f32>) -> ShadowRay {
#if MEDIA
    var ray = ShadowRay(v.position, 0u, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), VACUUM);
#else
    var ray = ShadowRay(v.position, 0u, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0));
#endif
    let lens_point = camera_lens_point(lens);
    let raster = camera_raster(v.position, lens_point);
    if (raster.z <= 0.0 || !bsdf.valid) {
        return ray;
    }
    let to_camera = lens_point - v.position;
    let distance2 = dot(to_camera, to_camera);
    let distance = sqrt(distance2);
    let direction = to_camera / distance;
    let e = bsdf_eval(bsdf, direction);
    if (is_black(e.f)) {
        return ray;
    }
    // The density with which the camera picks this vertex, per unit area at the vertex.
    let camera_pdf_a = camera_pdf_w(raster.z) * e.cos_gen / distance2;
    let n_light = f32(PIXELS);
    var weight = 1.0;
    if (!LIGHT_TRACE_ONLY) {
        let reverse = e.pdf_reverse * bsdf.continuation;
        let w_light = mis_pow(camera_pdf_a / n_light) * (counts.merge + v.d_vcm + v.d_vc * mis_pow(reverse));
        weight = 1.0 / (1.0 + w_light);
    }
    let pixel = min(u32(raster.y), u32(camera.height) - 1u) * WIDTH + min(u32(raster.x), WIDTH - 1u);
    ray.pixel = pixel;
    ray.direction = direction;
    ray.distance = distance;
    ray.contribution = v.throughput * e.f * (weight * camera_pdf_a / n_light);
    return ray;
}

// Samples the next direction with Russian roulette (continuation probability from the
// albedo) and updates throughput and MIS quantities; false when the sub-path ends. Used by
// light and camera sub-paths alike (`bsdf.adjoint` tells them apart). d_vcm of the next
// vertex stands for the strategy connecting the current vertex to it, always a vertex
// connection (counted `counts.connect` times); d_vc gains the strategies that end at the
// current vertex: the one d_vcm stood for and a merge there (`counts.merge`). Without
// connections (`counts.vc` false) d_vc is VCM's dVM with merging alone, which gains 1, the
// merge at the current vertex.
struct Scatter {
    origin: vec3<f32>,
    direction: vec3<f32>,
    throughput: vec3<f32>,
    d_vcm: f32,
    d_vc: f32,
    alive: bool,
}

fn scatter(bsdf: Bsdf, s: Surface, throughput: vec3<f32>, d_vcm: f32, d_vc: f32, counts: MisCounts, rng: ptr<function, u32>) -> Scatter {
    var r = Scatter(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    let u = vec3<f32>(rng_vec2(rng), rng_f32(rng));
    let roulette_u = rng_f32(rng);
    if (!bsdf.valid) {
        return r;
    }
    let smp = bsdf_sample(bsdf, u);
    if (is_black(smp.f) || roulette_u >= bsdf.continuation) {
        return r;
    }
    let q = bsdf.continuation;
    let pdf = smp.pdf * q;
    if (smp.specular) {
        r.d_vcm = 0.0;
        r.d_vc = mis_clamp(d_vc * mis_pow(smp.cos_gen));
    } else {
        let reverse = bsdf_eval(bsdf, smp.direction).pdf_reverse * q;
        let ending_here = select(1.0, counts.merge + d_vcm, counts.vc);
        r.d_vc = mis_clamp(mis_pow(smp.cos_gen / pdf) * (d_vc * mis_pow(reverse) + ending_here));
        r.d_vcm = mis_clamp(mis_pow(counts.connect / pdf));
    }
    r.throughput = throughput * smp.f * (smp.cos_gen / pdf);
    r.origin = offset_ray_origin(s.position, side_normal(s.normal, smp.direction), s.extent);
    r.direction = smp.direction;
    r.alive = true;
    return r;
}

// Continues a light sub-path from its current vertex (strategies counted as `counts`, see
// `scatter`); false when it ends.
fn light_path_scatter(p: ptr<function, LightPath>, s: Surface, bsdf: Bsdf, counts: MisCounts) -> bool {
    var rng = (*p).rng;
    let r = scatter(bsdf, s, (*p).throughput, (*p).d_vcm, (*p).d_vc, counts, &rng);
    (*p).rng = rng;
    if (!r.alive) {
        return false;
    }
    (*p).origin = r.origin;
    (*p).direction = r.direction;
    (*p).throughput = r.throughput;
    (*p).d_vcm = r.d_vcm;
    (*p).d_vc = r.d_vc;
#if MEDIA
    (*p).medium = medium_after(s.material, s.normal, r.direction, (*p).medium);
#endif
    return true;
}
