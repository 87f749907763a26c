// Light Vertex Cache BPT (Davidovic et al. 2014): phase 1 traces PATHS light sub-paths,
// splats t = 1 and stores every vertex a connection can use in one global cache; phase 2
// traces camera sub-paths (shaders/bpt/lvc_camera.wgsl), each non-delta vertex connecting to
// LVC_CONNECTIONS cache vertices picked uniformly (`lvc_connection`, here). A cache of M vertices from PATHS light sub-paths, sampled
// n times, estimates one light sub-path's connections with weight M / (n PATHS); in the MIS
// the connections count n / LVC_AVERAGE_LENGTH (the measured M / PATHS) against the other
// strategies. With LVC_MEASURING the light phase only counts the vertices it would store.
// The cache is put in sub-path order after the light phase by the engine's operators (an
// exclusive scan of the vertices per sub-path, a scatter of their indices, a gather of the
// vertices; graphs/bpt-lvc.ron), so every layout picks the same vertices for the same seed.

// Connections per camera vertex: ceil of the measured average (at least 1).
fn lvc_connections() -> u32 {
    return max(u32(ceil(LVC_AVERAGE_LENGTH)), 1u);
}

// The count of the connection strategies in the MIS (see `scatter`).
fn lvc_eta() -> f32 {
    return f32(lvc_connections()) / max(LVC_AVERAGE_LENGTH, 1e-3);
}

// Pass `lvc_light_generate` (Start over the light sub-paths): counts the sub-path for the
// measured average, then starts it as light tracing does.
fn lvc_light_generate(p: ptr<function, LightPath>, index: u32) -> bool {
    count(COUNTER_LVC_PATHS, 1u);
    return light_generate_stratified(p, index, LVC_LIGHT_STARTS);
}

// Pass `lvc_bounce` (Loop): at the light sub-path's new vertex, the t = 1 splat, the vertex
// into the cache (`lvc_store`), and the next direction.
fn lvc_bounce(p: ptr<function, LightPath>) -> bool {
    var stored = lvc_none_stored();
    return lvc_light_visit(p, mis_counts(lvc_eta()), 2u, &stored);
}

// `lvc_store`'s place of a vertex it did not store.
const LVC_NOT_STORED: u32 = 0xffffffffu;

// The vertex `lvc_light_visit` stored: its place in `lvc_staging` (LVC_NOT_STORED for none)
// and its position.
struct LvcStored {
    index: u32,
    position: vec3<f32>,
}

fn lvc_none_stored() -> LvcStored {
    return LvcStored(LVC_NOT_STORED, vec3<f32>(0.0));
}

// A light sub-path of LVC-BPT or VCM at its new vertex, strategies counted as `counts`: the
// vertex into the cache when a camera sub-path can still reach it with `reach` segments (2
// for a connection, 1 for a merge; its place and position into `stored`, left as it was
// otherwise), the t = 1 splat (with connections), and the next direction; false when the
// sub-path ends.
fn lvc_light_visit(p: ptr<function, LightPath>, counts: MisCounts, reach: u32, stored: ptr<function, LvcStored>) -> bool {
    let a = light_path_land(p);
    if (!a.alive) {
        return false;
    }
    let s = a.s;
    let bsdf = a.bsdf;
    if (!bsdf.is_delta) {
        let v = light_vertex_at(*p, s);
        if ((*p).length + reach <= MAX_PATH_LENGTH) {
            *stored = LvcStored(lvc_store(p, v), v.position);
        }
        if (counts.vc && !LVC_MEASURING && (*p).length + 1u <= MAX_PATH_LENGTH) {
            var rng = (*p).rng;
            let lens = camera_lens_sample(&rng);
            (*p).rng = rng;
            let ray = light_vertex_to_camera(v, bsdf, counts, lens);
            if (!is_black(ray.contribution)) {
                emit_splat(ray);
            }
        }
    }
    if ((*p).length + 2u > MAX_PATH_LENGTH) {
        return false;
    }
    return light_path_scatter(p, s, bsdf, counts);
}

// Stores light vertex `v` of sub-path `p` in arrival order in `lvc_staging` (counted as
// overflow when the cache is full), with its sub-path (`lvc_owner`) and its rank along the
// sub-path (`lvc_rank`) for the scatter that puts the cache in sub-path order; the measuring
// frame only counts it. Returns its place in `lvc_staging`, or LVC_NOT_STORED.
fn lvc_store(p: ptr<function, LightPath>, v: LightVertex) -> u32 {
    count(COUNTER_LVC_STORED, 1u);
    if (LVC_MEASURING) {
        return LVC_NOT_STORED;
    }
    let i = atomicAdd(&lvc_count, 1u);
    if (i < arrayLength(&lvc_staging)) {
        let rank = lvc_path_count[(*p).index];
        lvc_path_count[(*p).index] = rank + 1u;
        lvc_staging[i] = v;
        lvc_owner[i] = (*p).index;
        lvc_rank[i] = rank;
        return i;
    }
    count(COUNTER_LVC_OVERFLOW, 1u);
    return LVC_NOT_STORED;
}

// The connections camera vertex `visit` makes: `lvc_connections()` at a non-delta vertex with
// `connect`, else none.
fn lvc_connections_at(visit: CameraVisit, connect: bool) -> u32 {
    return select(0u, lvc_connections(), connect && !visit.a.bsdf.is_delta);
}

// The vertices in the cache this frame.
fn lvc_cached() -> u32 {
    return min(atomicLoad(&lvc_count), arrayLength(&lvc_cache));
}

// The connection of camera vertex `visit` of sub-path `p` to the vertex that `u` picks
// uniformly among the cache's `m` (`lvc_cached()`, loaded once a vertex): a black
// contribution where there is none, or the path would be too long. A cache of M vertices from
// PATHS light sub-paths, sampled n times, estimates one light sub-path's connections with
// weight M / (n PATHS).
fn lvc_connection(p: CameraSubpath, visit: CameraVisit, counts: MisCounts, m: u32, u: f32) -> ShadowRay {
    if (m == 0u) {
        return ShadowRay();
    }
    let v = lvc_cache[min(u32(u * f32(m)), m - 1u)];
    if (light_vertex_length(v) + 1u + p.length > MAX_PATH_LENGTH) {
        return ShadowRay();
    }
    var ray = bpt_connect(p, visit.a.s, visit.a.bsdf, v, counts);
    ray.contribution *= f32(m) / (f32(lvc_connections()) * f32(PATHS));
    return ray;
}
