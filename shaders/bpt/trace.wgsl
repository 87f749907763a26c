// Pass `bpt_trace` (Loop): finds the closest hit of the camera sub-path's ray.

fn bpt_trace(p: ptr<function, BptPath>) -> bool {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*p).length == 0u), 1u);
    let hit = trace_closest((*p).origin, (*p).direction, INFINITE_DISTANCE);
    (*p).hit_t = select(-1.0, hit.t, hit.found);
    (*p).hit_primitive = hit.primitive;
    (*p).hit_uv = hit.uv;
    (*p).length += 1u;
    return true;
}
