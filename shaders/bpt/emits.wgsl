// The parts of bidirectional path tracing that send shadow rays through the graph's `shadow`
// stream (NaiveBPT, StreamingBPT): a graph that includes them declares that stream. The rest
// of BPT (shaders/bpt/path.wgsl) returns its rays to the caller.

// What a light sub-path of NaiveBPT or StreamingBPT did at a vertex (`bpt_light_visit`).
struct LightVisit {
    vertex: LightVertex,
    store: bool,                // whether a connection can use the vertex
    go_on: bool,                // whether the sub-path continues
}

// Light sub-path `lp` of NaiveBPT or StreamingBPT at the vertex it arrived at: the t = 1
// splat (through the `shadow` stream, into the film slot from `film_base` on), the vertex to
// store, and the next direction.
fn bpt_light_visit(lp: ptr<function, LightPath>, a: Arrival, film_base: u32) -> LightVisit {
    var r: LightVisit;
    r.store = false;
    if (!a.bsdf.is_delta) {
        r.vertex = light_vertex_at(*lp, a.s);
        var rng = (*lp).rng;
        let lens = camera_lens_sample(&rng);
        (*lp).rng = rng;
        var ray = light_vertex_to_camera(r.vertex, a.bsdf, mis_counts(1.0), lens);
        ray.pixel += film_base;
        if (!is_black(ray.contribution)) {
            emit_shadow(ray);
        }
        r.store = (*lp).length + 2u <= MAX_PATH_LENGTH;
    }
    r.go_on = (*lp).length + 2u <= MAX_PATH_LENGTH && light_path_scatter(lp, a.s, a.bsdf, mis_counts(1.0));
    return r;
}

// Emits the visit's s = 1 shadow ray through the `shadow` stream, if it has one.
fn camera_emit_direct(v: CameraVisit) {
    if (!is_black(v.direct.contribution)) {
        emit_shadow(v.direct);
    }
}
