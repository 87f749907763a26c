// The photon structures' contract (shaders/pm/photon.wgsl) for the range-query test
// (tests/data/graphs/pm_query.ron): the cube and the build radius come from the host, a query
// is a centre and a radius, and each query sums what the gather hands to merge_photon: the
// photons found, a sum and a xor of their hashed ids (carried in throughput.x, exact as f32),
// the sum of their weights, and the first QUERY_LISTED ids with their weights.

struct QueryScene {
    origin: vec3<f32>,
    extent: f32,
    cell_radius: f32,
}

const QUERY_LISTED: u32 = 32u;

struct QueryResult {
    found: atomic<u32>,
    sum: atomic<u32>,
    xor: atomic<u32>,
    weight: atomic<u32>,    // the bits of an f32
    // Id and weight (its bits) of the first photons found.
    listed: array<vec2<u32>, QUERY_LISTED>,
}

// The photon pass's item as the original stochastic grid's insertion (PM_STRUCTURE 2)
// reads it: the photon it stored last (shaders/pm/light.wgsl).
struct PhotonPath {
    stored: u32,
}

const PM_NONE: u32 = 0xffffffffu;

struct MergePath {
    position: vec3<f32>,
    radius: f32,
    query: u32,
}

struct Merge {
    position: vec3<f32>,
    radius: f32,
    pending: bool,
    query: u32,
    sum: u32,
    xor: u32,
    weight: f32,
}

fn pm_cell_radius() -> f32 {
    return scene.cell_radius;
}

fn pm_origin() -> vec3<f32> {
    return scene.origin;
}

fn pm_extent() -> f32 {
    return scene.extent;
}

// Pass `query_load` (Start over QUERIES): query `index`, its result cleared.
fn query_load(p: ptr<function, MergePath>, index: u32) -> bool {
    atomicStore(&film[index].found, 0u);
    atomicStore(&film[index].sum, 0u);
    atomicStore(&film[index].xor, 0u);
    atomicStore(&film[index].weight, 0u);
    let q = queries[index];
    *p = MergePath(q.xyz, q.w, index);
    return true;
}

// Pass `photon_insert` (Start over the stored photons): a sub-path that stored photon `index`.
fn photon_insert(p: ptr<function, PhotonPath>, index: u32) -> bool {
    (*p).stored = index;
    return true;
}

// Pass `photon_insert_end` (Loop, after the insertion): one insertion per photon.
fn photon_insert_end(p: ptr<function, PhotonPath>) -> bool {
    return false;
}

// Pass `query_end` (Loop, after the gather): one gather per query.
fn query_end(p: ptr<function, MergePath>) -> bool {
    return false;
}

fn merge_begin(p: MergePath) -> Merge {
    return merge_resume(p);
}

fn merge_resume(p: MergePath) -> Merge {
    return Merge(p.position, p.radius, true, p.query, 0u, 0u, 0.0);
}

// A well-mixed hash of a photon's id (the test computes the same).
fn query_hash(id: u32) -> u32 {
    var x = id;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn merge_photon(m: ptr<function, Merge>, photon: Photon, weight: f32) {
    let id = u32(photon.throughput.x);
    let slot = atomicAdd(&film[(*m).query].found, 1u);
    if (slot < QUERY_LISTED) {
        film[(*m).query].listed[slot] = vec2<u32>(id, bitcast<u32>(weight));
    }
    let h = query_hash(id);
    (*m).sum += h;
    (*m).xor ^= h;
    (*m).weight += weight;
}

fn merge_end(p: ptr<function, MergePath>, m: Merge) {
    let q = m.query;
    atomicAdd(&film[q].sum, m.sum);
    atomicXor(&film[q].xor, m.xor);
    var old = atomicLoad(&film[q].weight);
    loop {
        let r = atomicCompareExchangeWeak(&film[q].weight, old, bitcast<u32>(bitcast<f32>(old) + m.weight));
        if (r.exchanged) {
            break;
        }
        old = r.old_value;
    }
}
