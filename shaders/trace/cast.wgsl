// Passes `trace_primary`, `trace_ao` and `trace_diffuse` (Start over PATHS), each its own
// kernel so that its GPU time is the traversal of one kind of ray alone: each casts its ray
// of the index (rays of `trace_make`, made once) and stores one word of the result, the hit
// distance of a closest-hit ray (-1 for none) or 1 / 0 for an occluded / open any-hit ray.
// A missing ray (t_max 0) stores -1 and counts nothing. With TRACE_STATS each also counts the
// nodes its rays visit and the primitives they test (nodes_*, tests_*). With TRACE_SORT
// `trace_diffuse`'s index i casts the diffuse ray `trace_order[i]`, in the order of their keys.

fn trace_closest_into(slot: u32) {
    let ray = trace_rays[slot];
    if (ray.t_max <= 0.0) {
        trace_results[slot] = -1.0;
        return;
    }
    let hit = trace_closest(ray.origin, ray.direction, ray.t_max);
    trace_results[slot] = select(-1.0, hit.t, hit.found);
}

fn trace_primary(s: ptr<function, TraceItem>, index: u32) -> bool {
#if TRACE_STATS
    trace_stats = vec2<u32>(COUNTER_NODES_PRIMARY, COUNTER_TESTS_PRIMARY) + 1u;
#endif
    count(COUNTER_RAYS_PRIMARY, 1u);
    trace_closest_into(index);
    return false;
}

fn trace_ao(s: ptr<function, TraceItem>, index: u32) -> bool {
    let slot = PATHS + index;
    let ray = trace_rays[slot];
    if (ray.t_max <= 0.0) {
        trace_results[slot] = -1.0;
        return false;
    }
    count(COUNTER_RAYS_OCCLUSION, 1u);
#if TRACE_STATS
    trace_stats = vec2<u32>(COUNTER_NODES_AO, COUNTER_TESTS_AO) + 1u;
#endif
    trace_results[slot] = select(0.0, 1.0, trace_any(ray.origin, ray.direction, ray.t_max));
    return false;
}

fn trace_diffuse(s: ptr<function, TraceItem>, index: u32) -> bool {
#if TRACE_SORT
    let slot = 2u * PATHS + trace_order[index];
#else
    let slot = 2u * PATHS + index;
#endif
    if (trace_rays[slot].t_max > 0.0) {
        count(COUNTER_RAYS_DIFFUSE, 1u);
    }
#if TRACE_STATS
    trace_stats = vec2<u32>(COUNTER_NODES_DIFFUSE, COUNTER_TESTS_DIFFUSE) + 1u;
#endif
    trace_closest_into(slot);
    return false;
}
