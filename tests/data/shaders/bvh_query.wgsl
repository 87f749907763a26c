// Pass `query`: results[i] = (closest t or -1, closest primitive (bits), any hit below rays[2i].w, 0).

struct Query {
    index: u32,
}

fn query(q: ptr<function, Query>, index: u32) -> bool {
    let o = rays[2u * index];
    let d = rays[2u * index + 1u].xyz;
    let hit = trace_closest(o.xyz, d, INFINITE_DISTANCE);
    let any = trace_any(o.xyz, d, o.w);
    results[index] = vec4<f32>(select(-1.0, hit.t, hit.found), bitcast<f32>(hit.primitive), select(0.0, 1.0, any), 0.0);
    return false;
}
