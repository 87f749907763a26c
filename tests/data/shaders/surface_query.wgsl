// Pass `surface_query` of the test graph surface_query.ron.

struct SurfaceQuery {
    index: u32,
}

fn surface_query(q: ptr<function, SurfaceQuery>, index: u32) -> bool {
    let tex = queries[3u * index];
    let o = queries[3u * index + 1u].xyz;
    let d = queries[3u * index + 2u];
    if (tex.x >= 0.0) {
        results[4u * index] = texture_sample(u32(tex.x), tex.yz);
    }
    let hit = trace_closest(o, d.xyz, INFINITE_DISTANCE);
    let any = trace_any(o, d.xyz, d.w);
    results[4u * index + 1u] = vec4<f32>(select(0.0, 1.0, hit.found), hit.t, select(0.0, 1.0, any), f32(hit.primitive));
    if (hit.found) {
        let s = surface_at(hit, o, d.xyz);
        results[4u * index + 2u] = vec4<f32>(s.shading_normal, 0.0);
        results[4u * index + 3u] = vec4<f32>(s.tex, 0.0, 0.0);
    }
    (*q).index = index;
    return false;
}
