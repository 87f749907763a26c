// Pass `ao_occlusion` (Step over OcclusionRay): 1 for the pixel when nothing lies within
// AO_DISTANCE.

fn ao_occlusion(ray: ptr<function, OcclusionRay>) -> bool {
    count(COUNTER_RAYS_OCCLUSION, 1u);
    if (!trace_any((*ray).origin, (*ray).direction, AO_DISTANCE)) {
        film_add((*ray).pixel, vec3<f32>(1.0));
    }
    return false;
}
