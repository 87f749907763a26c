// Passes `trace_primary`, `trace_ao` and `trace_diffuse` (Start over PATHS), each its own
// kernel so that its GPU time is the traversal of one kind of ray alone: each casts its ray
// of the index (rays of `trace_make`, made once) and stores one word of the result, the hit
// distance of a closest-hit ray (-1 for none) or 1 / 0 for an occluded / open any-hit ray.
// A missing ray (t_max 0) stores -1 and counts nothing. With TRACE_STATS each also counts the
// nodes its rays visit and the primitives they test (nodes_*, tests_*). With TRACE_SORT
// `trace_diffuse`'s index i casts the diffuse ray `trace_order[i]`, in the order of their keys.
// With TRACE_RAYS_PER_THREAD above 1 each thread of `trace_diffuse` casts that many diffuse
// rays, on the CWBVH interleaved in one loop (`trace_diffuse_interleaved`).

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

// The slot of the diffuse ray that index `i` casts.
fn trace_diffuse_slot(i: u32) -> u32 {
#if TRACE_SORT
    return 2u * PATHS + trace_order[i];
#else
    return 2u * PATHS + i;
#endif
}

// Thread `index` casts the diffuse rays index, index + T, index + 2 T, ... (T threads, each
// with at most TRACE_RAYS_PER_THREAD rays).
fn trace_diffuse(s: ptr<function, TraceItem>, index: u32) -> bool {
#if TRACE_STATS
    trace_stats = vec2<u32>(COUNTER_NODES_DIFFUSE, COUNTER_TESTS_DIFFUSE) + 1u;
#endif
#if CWBVH
    if (TRACE_RAYS_PER_THREAD > 1u) {
        trace_diffuse_interleaved(index);
        return false;
    }
#endif
    let threads = (PATHS + TRACE_RAYS_PER_THREAD - 1u) / TRACE_RAYS_PER_THREAD;
    for (var i = index; i < PATHS; i += threads) {
        let slot = trace_diffuse_slot(i);
        if (trace_rays[slot].t_max > 0.0) {
            count(COUNTER_RAYS_DIFFUSE, 1u);
        }
        trace_closest_into(slot);
    }
    return false;
}

#if CWBVH
// The rays of `trace_diffuse`'s thread `index` one after another in one loop of CWBVH walk
// steps: a ray that ends is stored and the next one starts at once, so that the thread does
// not idle while its subgroup's other rays walk on (Aila and Laine 2009, dynamic fetch, with
// the rays dealt to threads beforehand).
fn trace_diffuse_interleaved(index: u32) {
    let threads = (PATHS + TRACE_RAYS_PER_THREAD - 1u) / TRACE_RAYS_PER_THREAD;
    var w: CwbvhWalk;
    var i = index;
    var slot = 0u;
    var walking = false;
    loop {
        if (!walking) {
            if (i >= PATHS) {
                break;
            }
            slot = trace_diffuse_slot(i);
            i += threads;
            let ray = trace_rays[slot];
            if (ray.t_max <= 0.0) {
                trace_results[slot] = -1.0;
                continue;
            }
            count(COUNTER_RAYS_DIFFUSE, 1u);
            cwbvh_walk_start(&w, ray.origin, ray.direction, ray.t_max, false);
            walking = true;
        }
        if (!cwbvh_walk_step(&w)) {
            trace_results[slot] = select(-1.0, w.hit.t, w.hit.found);
            walking = false;
        }
    }
}
#endif
