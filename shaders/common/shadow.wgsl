// Pass `shadow` (Step over ShadowRay): adds the contribution to its pixel unless something
// lies on the segment.

fn shadow(ray: ptr<function, ShadowRay>) -> bool {
    count(COUNTER_RAYS_SHADOW, 1u);
#if MEDIA
    // Times the transmittance of the media on the segment, through index-matched boundaries.
    let tr = media_shadow_transmittance((*ray).origin, (*ray).direction, (*ray).distance, (*ray).medium);
    if (!is_black(tr)) {
        film_add((*ray).pixel, (*ray).contribution * tr);
    }
#else
    if (!trace_any((*ray).origin, (*ray).direction, (*ray).distance)) {
        film_add((*ray).pixel, (*ray).contribution);
    }
#endif
    return false;
}
