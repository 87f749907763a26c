// Photons: the vertices of light sub-paths that density estimation gathers (photon mapping,
// shaders/pm). The light phase stores them in arrival order in `pm_staging` (PM_CAPACITY
// slots) and counts them in `pm_count` (which may exceed the capacity: the rest is
// overflow); a spatial structure is then built over them and queried at camera vertices.
//
// The contract between the estimators and the structures (full hash grid: grid.wgsl,
// stochastic hash grids: stochastic.wgsl, kD-tree: kdtree.wgsl), so that any structure serves
// any estimator, and a test can query a structure with clouds of its own:
// - resources `pm_staging: array<Photon>` and `pm_count: atomic<u32>`;
// - `pm_cell_radius()`: the query radius the structure is built for this frame;
//   `pm_origin()` and `pm_extent()`: a cube [origin, origin + extent]^3 holding every photon
//   (the scene's bounding sphere's cube);
// - the camera chain's item `MergePath`, and a `Merge` with the fields `position`, `radius`
//   and `pending`: `merge_begin(path)` says whether the path has a query pending and where;
//   a structure's gather pass (Loop over MergePath) calls `merge_photon(&m, photon, weight)`
//   once for every stored photon with `pm_in_range(photon.position, m.position, m.radius)`
//   (weight 1; a stochastic grid's kept photon stands for `weight` photons), then
//   `merge_end(&path, m)`, and returns true. A gather may split a query over threads: each
//   part begins with `merge_resume(path)` (not counted again as a query) and ends with
//   `merge_end`, which adds the part's sum (shaders/pm/grid.wgsl).

// Needs shaders/lib/scene.wgsl (the octahedral code of directions).

// A photon (32 bytes): where it landed (moved off the surface to the side it arrived from, as
// a cache vertex is: `light_vertex_position`), PBPM's MIS quantity, the light sub-path's throughput
// there, and the direction it arrived from (octahedral, 12 bits a component) with the
// segments from the light (7 bits) and whether its sub-path left a delta light through delta
// lobes alone (the top bit, `photon_delta_chain`: light no camera sub-path can reach by
// continuing, shaders/pm/camera.wgsl).
struct Photon {
    position: vec3<f32>,
    d_vm: f32,
    throughput: vec3<f32>,
    direction_length: u32,
}

// One stored photon, the item of the passes over them.
struct PhotonSlot {
    index: u32,
}

// A direction in 24 bits: its octahedral code (the scene's, two snorm16 components) with
// each component cut to its top 12 bits.
fn octahedral_24(code: u32) -> u32 {
    return ((code >> 4u) & 0xfffu) | (((code >> 20u) & 0xfffu) << 12u);
}

// The unit direction of a 24-bit code (the bits above 24 are ignored).
fn decode_octahedral_24(w: u32) -> vec3<f32> {
    return decode_octahedral(((w & 0xfffu) << 4u) | (((w >> 12u) & 0xfffu) << 20u));
}

const PHOTON_DELTA_CHAIN: u32 = 0x80000000u;

// Packs the direction towards the previous vertex (24 bits), the sub-path's length and
// whether it came from a delta light through delta lobes alone.
fn photon_pack(towards: vec3<f32>, length: u32, delta_chain: bool) -> u32 {
    let chain = select(0u, PHOTON_DELTA_CHAIN, delta_chain);
    return octahedral_24(encode_octahedral(towards)) | (min(length, 127u) << 24u) | chain;
}

// The direction towards the previous vertex of the light sub-path (unit length).
fn photon_direction(p: Photon) -> vec3<f32> {
    return decode_octahedral_24(p.direction_length);
}

// Segments from the light to the photon.
fn photon_length(p: Photon) -> u32 {
    return (p.direction_length >> 24u) & 0x7fu;
}

// Whether the photon's sub-path left a delta light and was scattered by delta lobes alone.
fn photon_delta_chain(p: Photon) -> bool {
    return (p.direction_length & PHOTON_DELTA_CHAIN) != 0u;
}

// The photons stored this frame (at most the capacity).
fn photon_total() -> u32 {
    return min(atomicLoad(&pm_count), arrayLength(&pm_staging));
}

// Whether a photon at `position` is within `radius` of `center`: the one test every
// structure applies, so that all of them find the same photons.
fn pm_in_range(position: vec3<f32>, center: vec3<f32>, radius: f32) -> bool {
    let d = position - center;
    return dot(d, d) <= radius * radius;
}
