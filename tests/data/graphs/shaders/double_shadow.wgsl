// Pass `shadow` of the test graph pt-double-nee: path tracing's shadow pass
// (shaders/common/shadow.wgsl) with a deliberate bug, the contribution added twice.
fn shadow(ray: ptr<function, ShadowRay>) -> bool {
    count(COUNTER_RAYS_SHADOW, 1u);
    if (!trace_any((*ray).origin, (*ray).direction, (*ray).distance)) {
        film_add((*ray).pixel, 2.0 * (*ray).contribution);
    }
    return false;
}
