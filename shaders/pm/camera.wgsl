// The camera side of photon mapping: camera sub-paths that estimate the density of photons
// at their vertices, as Davidovic et al. 2014 (section 6, Figure 6) define the three
// estimators (PM_MODE):
// - PPM (PM_PPM): through delta vertices only; density estimation with the full BSDF at the
//   first non-delta vertex, which ends the sub-path;
// - SPPM (PM_SPPM): at each vertex, density estimation with the BSDF's diffuse part, and the
//   sub-path goes on through the other lobes (glossy and delta) only; it ends at a vertex
//   without them. Every light it hits counts (the glossy continuation is the only estimate of
//   the light reaching the camera through those lobes). A continued sub-path never hits a
//   delta light, so the light that reaches a vertex from one through delta lobes alone (a
//   caustic or the direct light of a point light or the sun, seen in a glossy floor) would be
//   lost to the glossy lobes: those photons (`photon_delta_chain`) are estimated with the
//   whole BSDF, at every vertex with a diffuse or a non-delta glossy lobe (`sppm_delta_chains`);
// - PBPM (PM_PBPM): continues as a path tracer (full BSDF, Russian roulette) and estimates
//   the density at every non-delta vertex, combined by MIS over the vertices (dVM,
//   shaders/pm/scatter.wgsl).
// PPM and PBPM count a light the camera sees directly or through delta vertices only: every
// other path reaches the camera through a merge. The radius of iteration i (from 1) is
// r_i = PM_RADIUS scene radius i^((PM_ALPHA - 1) / 2) (Knaus and Zwicker 2011), the same for
// the structure, the query, the kernel 1 / (pi r^2 N) and the MIS, where N is the light
// sub-paths an iteration merges (`pm_merge_paths`). A frame is one iteration, or
// PM_ITERATIONS (VCM's): its iterations i = frame PM_ITERATIONS + 1, ... take the radius of
// the first.

const PM_PPM: u32 = 0u;
const PM_SPPM: u32 = 1u;
const PM_PBPM: u32 = 2u;

#if LIGHT_DELTA
const PM_DELTA_LIGHTS: bool = true;
#else
const PM_DELTA_LIGHTS: bool = false;
#endif

// Whether SPPM estimates the photons of delta chains with the whole BSDF (see the top): only
// in scenes with delta lights, whose photons can be such.
fn sppm_delta_chains() -> bool {
    return PM_MODE == PM_SPPM && PM_DELTA_LIGHTS;
}

const MERGE_SPECULAR_PATH: u32 = 1u;   // every vertex so far was left through a delta lobe
const MERGE_PENDING: u32 = 2u;         // a density estimation waits at the vertex below
const MERGE_ALIVE: u32 = 4u;           // the sub-path goes on after this vertex

// The merge radius of this frame's iterations.
fn pm_radius() -> f32 {
    return PM_RADIUS * scene.radius * pow(f32(frame.index * PM_ITERATIONS) + 1.0, (PM_ALPHA - 1.0) * 0.5);
}

// The light sub-paths whose vertices one iteration merges: the frame's, or their share of
// one of the frame's PM_ITERATIONS iterations.
fn pm_merge_paths() -> f32 {
    return f32(PM_LIGHT_PATHS / PM_ITERATIONS);
}

// The structures' contract (shaders/pm/photon.wgsl): built for this frame's radius (times
// PM_CELL_SCALE: the hash grids' cells have side 2 PM_CELL_SCALE r), over the cube around the
// scene's bounding sphere.
fn pm_cell_radius() -> f32 {
    return pm_radius() * PM_CELL_SCALE;
}

fn pm_origin() -> vec3<f32> {
    return scene.center - vec3<f32>(scene.radius);
}

fn pm_extent() -> f32 {
    return 2.0 * scene.radius;
}

// A density estimation left pending at a camera vertex for a gather pass (photon mapping's
// and VCM's): the vertex, what its BSDF is set up from (material, texture coordinates, the
// direction towards the previous vertex and the normals), unrounded, so that the gather's BSDF
// is the one the vertex had (VCM merging at the vertex renders what PBPM and VCM's gather
// render); the camera sub-path's throughput and dVM there, and its length (segments).
struct PendingMerge {
    position: vec3<f32>,
    material: u32,
    throughput: vec3<f32>,
    d_vm: f32,
    fix: vec3<f32>,
    length: u32,
    tex: vec2<f32>,
    normals: VertexNormals,
}

// The estimation to leave pending at surface `s`, reached from `towards`.
fn pending_merge_at(s: Surface, towards: vec3<f32>, throughput: vec3<f32>, d_vm: f32, length: u32) -> PendingMerge {
    var m: PendingMerge;
    m.position = s.position;
    m.material = s.material;
    m.throughput = throughput;
    m.d_vm = d_vm;
    m.fix = towards;
    m.length = length;
    m.tex = s.tex;
    m.normals = vertex_normals(s);
    return m;
}

// The BSDF at a pending estimation's vertex, as the camera sub-path set it up there.
fn pending_merge_bsdf(m: PendingMerge) -> Bsdf {
    return vertex_bsdf(material_at(m.material, m.tex), m.normals, m.fix);
}

// A camera sub-path between passes, with the density estimation pending at its last vertex.
struct MergePath {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
    length: u32,            // camera segments traced so far
    throughput: vec3<f32>,
    rng: u32,
    d_vm: f32,
    flags: u32,
    hit: PathHit,           // the last traced ray's hit (t < 0: it escaped)
    merge: PendingMerge,
}

// A density estimation under way: the query and the sums of the photons it found. Where the
// BSDF is a Lambertian (PPM and SPPM), its value `lambertian_f` comes out of the sum: `flux`
// sums the throughputs of the photons arriving from above the surface (`merge_sum`).
struct Merge {
    position: vec3<f32>,
    radius: f32,
    pending: bool,
    bsdf: Bsdf,
    d_vm: f32,
    length: u32,
    sum: vec3<f32>,
    lambertian_f: vec3<f32>,
    flux: vec3<f32>,
}

// Pass `pm_camera` (Start over PATHS): the camera ray of sample `index` (pixel index % PIXELS
// in tile order, so that a workgroup's queries are close).
fn pm_camera(p: ptr<function, MergePath>, index: u32) -> bool {
    var rng = rng_seed(frame.seed ^ 0x9e3779b9u, frame.index, index);
    let pixel = camera_tiled_pixel(index % PIXELS);
    let ray = camera_jittered_ray(pixel, &rng);
    (*p).origin = ray.origin;
    (*p).pixel = pixel;
    (*p).direction = ray.direction;
    (*p).length = 0u;
    (*p).throughput = vec3<f32>(1.0);
    (*p).rng = rng;
    (*p).d_vm = 0.0;
    (*p).flags = MERGE_SPECULAR_PATH | MERGE_ALIVE;
    return true;
}

// Pass `pm_trace` (Loop): the closest hit of the sub-path's ray.
fn pm_trace(p: ptr<function, MergePath>) -> bool {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*p).length == 0u), 1u);
    let hit = trace_closest((*p).origin, (*p).direction, INFINITE_DISTANCE);
    (*p).hit = path_hit(hit);
    (*p).length += 1u;
    return true;
}

// Whether light found by the sub-path at its current length counts (see the top).
fn merge_counts_emission(p: MergePath) -> bool {
    return PM_MODE == PM_SPPM || p.length == 1u || (p.flags & MERGE_SPECULAR_PATH) != 0u;
}

// Pass `pm_vertex` (Loop): at the sub-path's new vertex, the light found there, the density
// estimation to make (left pending for the structure's gather pass) and the next direction.
// Always true; `pm_continue` ends the sub-path.
fn pm_vertex(p: ptr<function, MergePath>) -> bool {
    (*p).flags &= ~(MERGE_PENDING | MERGE_ALIVE);
    let direction = (*p).direction;
    if (path_hit_escaped((*p).hit)) {
        let bg = background_radiance(direction);
        if (bg.w > 0.0 && merge_counts_emission(*p)) {
            film_add((*p).pixel, (*p).throughput * bg.xyz);
        }
        return true;
    }
    let s = path_hit_surface((*p).hit, (*p).origin, direction);
    let bsdf = surface_bsdf(s, -direction);
    if (s.light >= 0 && merge_counts_emission(*p)) {
        let le = area_light_radiance(u32(s.light), direction);
        if (le.w > 0.0) {
            film_add((*p).pixel, (*p).throughput * le.xyz);
        }
    }
    if (!bsdf.valid || (*p).length >= MAX_PATH_LENGTH) {
        return true;
    }
    (*p).d_vm = mis_clamp((*p).d_vm / mis_pow(abs(bsdf.fix.z)));
    var go_on = true;
    var next = bsdf;
    if (PM_MODE == PM_SPPM) {
        next = bsdf_glossy_part(bsdf);
        let rough = next.valid && !next.is_delta;
        if (bsdf_has_diffuse(bsdf) || (sppm_delta_chains() && rough)) {
            merge_leave_pending(p, s);
        }
        go_on = bsdf_has_glossy(bsdf);
    } else if (!bsdf.is_delta) {
        merge_leave_pending(p, s);
        go_on = PM_MODE == PM_PBPM;
    }
    if (go_on) {
        merge_scatter(p, next, s);
    }
    return true;
}

// Leaves the density estimation at surface `s` pending for the gather pass.
fn merge_leave_pending(p: ptr<function, MergePath>, s: Surface) {
    (*p).flags |= MERGE_PENDING;
    (*p).merge = pending_merge_at(s, -(*p).direction, (*p).throughput, (*p).d_vm, (*p).length);
}

// Continues the sub-path through `bsdf` (all of it, or SPPM's glossy part).
fn merge_scatter(p: ptr<function, MergePath>, bsdf: Bsdf, s: Surface) {
    var rng = (*p).rng;
    let r = pm_scatter(bsdf, s, (*p).throughput, (*p).d_vm, &rng);
    (*p).rng = rng;
    if (!r.alive) {
        return;
    }
    (*p).origin = r.origin;
    (*p).direction = r.direction;
    (*p).throughput = r.throughput;
    (*p).d_vm = r.d_vm;
    if (!r.specular) {
        (*p).flags &= ~MERGE_SPECULAR_PATH;
    }
    (*p).flags |= MERGE_ALIVE;
}

// Pass `pm_continue` (Loop, last): ends the sub-path when `pm_vertex` said so.
fn pm_continue(p: ptr<function, MergePath>) -> bool {
    return ((*p).flags & MERGE_ALIVE) != 0u;
}

// The density estimation pending at the sub-path's vertex, if any (the structures' contract),
// counted as `pm_queries`.
fn merge_begin(p: MergePath) -> Merge {
    if ((p.flags & MERGE_PENDING) == 0u) {
        var none: Merge;
        none.pending = false;
        return none;
    }
    count(COUNTER_PM_QUERIES, 1u);
    return merge_resume(p);
}

// A part of the density estimation pending at the sub-path's vertex (the structures'
// contract: a gather that splits a query over threads begins each part so; not counted
// again): this frame's radius, the BSDF there (SPPM's diffuse part, or its whole BSDF with
// `sppm_delta_chains`; a Lambertian's value apart: SPPM's diffuse part's) and nothing found yet.
fn merge_resume(p: MergePath) -> Merge {
    var m = merge_unset(p.merge);
    m.bsdf = pending_merge_bsdf(p.merge);
    if (PM_MODE == PM_SPPM) {
        let diffuse = bsdf_diffuse_part(m.bsdf);
        m.lambertian_f = bsdf_lambertian_f(diffuse);
        if (!sppm_delta_chains()) {
            m.bsdf = diffuse;
        }
    } else if (PM_MODE == PM_PPM) {
        m.lambertian_f = bsdf_lambertian_f(m.bsdf);
    }
    return m;
}

// A density estimation at `position` begun (counted as `pm_queries`) with its BSDF not yet set
// up: a query that finds nothing needs none (VCM's, whose queries mostly find none, set it up
// at their first vertex found, or take the one of the vertex they are made at).
fn merge_query_at(position: vec3<f32>, d_vm: f32, length: u32) -> Merge {
    count(COUNTER_PM_QUERIES, 1u);
    return merge_unset_at(position, d_vm, length);
}

// An estimation at `pending` with this frame's radius, nothing found yet and no BSDF.
fn merge_unset(pending: PendingMerge) -> Merge {
    return merge_unset_at(pending.position, pending.d_vm, pending.length);
}

// An estimation at `position` with this frame's radius, nothing found yet and no BSDF.
fn merge_unset_at(position: vec3<f32>, d_vm: f32, length: u32) -> Merge {
    return Merge(position, pm_radius(), true, Bsdf(), d_vm, length, vec3<f32>(0.0), vec3<f32>(-1.0), vec3<f32>(0.0));
}

// Adds a photon in range (counted as `pm_found`; the queries as `pm_queries`), standing for
// `weight` photons, to the estimation: the BSDF for the direction it arrived from (a
// Lambertian's value taken out of the sum, see `Merge`) times its throughput (the photon
// arrives at the query point), with PBPM's MIS weight. Photons that would make the path
// longer than MAX_PATH_LENGTH are left out.
fn merge_photon(m: ptr<function, Merge>, photon: Photon, weight: f32) {
    count(COUNTER_PM_FOUND, 1u);
    if (photon_length(photon) + (*m).length > MAX_PATH_LENGTH || !pm_merges_photon(*m, photon)) {
        return;
    }
    let towards = photon_direction(photon);
    if (sppm_delta_chains() && photon_delta_chain(photon)) {
        (*m).sum += bsdf_eval_merge((*m).bsdf, towards).f * photon.throughput * weight;
        return;
    }
    if ((*m).lambertian_f.x >= 0.0) {
        if (dot(towards, (*m).bsdf.frame.n) >= EPS_COSINE) {
            (*m).flux += photon.throughput * weight;
        }
        return;
    }
    var b = (*m).bsdf;
    if (sppm_delta_chains()) {
        b = bsdf_diffuse_part(b);
        if (!b.valid) {
            return;
        }
    }
    let e = bsdf_eval_merge(b, towards);
    if (is_black(e.f)) {
        return;
    }
    var w = weight;
    if (PM_MODE == PM_PBPM) {
        let w_light = photon.d_vm * mis_pow(e.pdf_forward * (*m).bsdf.continuation);
        let w_camera = (*m).d_vm * mis_pow(e.pdf_reverse * bsdf_continuation_towards((*m).bsdf, towards));
        w /= w_light + 1.0 + w_camera;
    }
    (*m).sum += e.f * photon.throughput * w;
}

// Hook: whether the density estimation `m` at a camera vertex (its position, radius, BSDF,
// camera sub-path length and dVM) merges `photon`, found within its radius, asked for every
// photon that keeps the path within MAX_PATH_LENGTH (`photon_length`, `photon_direction` and
// `photon_delta_chain` read its packed word). Default: every such photon.
fn pm_merges_photon(m: Merge, photon: Photon) -> bool {
    return true;
}

// The density estimation's kernel at `radius`: 1 / (pi r^2 N), N the iteration's light
// sub-paths.
fn merge_kernel(radius: f32) -> f32 {
    return 1.0 / (PI * radius * radius * pm_merge_paths());
}

// Adds the finished estimation, or a part of a split one, to the film: the sums over pi r^2 N.
fn merge_end(p: ptr<function, MergePath>, m: Merge) {
    if (!m.pending) {
        return;
    }
    (*p).flags &= ~MERGE_PENDING;
    let merged = (*p).merge.throughput * merge_sum(m) * merge_kernel(m.radius);
    film_add((*p).pixel, merged);
    film_add_biased((*p).pixel, merged);
}

// The estimation's sum of BSDF values times photon throughputs.
fn merge_sum(m: Merge) -> vec3<f32> {
    return m.sum + max(m.lambertian_f, vec3<f32>(0.0)) * m.flux;
}
