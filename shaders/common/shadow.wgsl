// Pass `shadow` (Step over ShadowRay): adds the contribution to its pixel unless something
// lies on the segment.

fn shadow(ray: ptr<function, ShadowRay>) -> bool {
    count(COUNTER_RAYS_SHADOW, 1u);
    if (!trace_any((*ray).origin, (*ray).direction, (*ray).distance)) {
        film_add((*ray).pixel, (*ray).contribution);
    }
    return false;
}
