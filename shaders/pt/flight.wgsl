#if MEDIA
// A camera path's free flight to its next vertex through participating media (MEDIA;
// docs/media.md), for pass `trace`. In a homogeneous medium a free flight picks the distance by
// one channel's extinction and weights it by all three (shaders/lib/media.wgsl); in a grid
// medium (MEDIA_GRID) it is delta tracking (shaders/lib/media_grid.wgsl).

// After `trace` found the closest hit of the path's ray: the free flight through the path's
// medium up to that hit. The path scatters in the medium (VERTEX_MEDIUM at hit.t) or reaches
// the surface (VERTEX_SURFACE); an index-matched boundary there is crossed without a vertex
// and the ray traced on from its far side, in the medium beyond it. The throughput takes each
// flight's weight; `gap` adds the distance the ray's origin moved, for MIS at a light it hits.
fn path_through_media(path: ptr<function, CameraPath>) {
    var rng = (*path).rng;
    (*path).vertex = VERTEX_SURFACE;
    for (var i = 0u; i < MEDIA_MAX_CROSSINGS; i++) {
        let escaped = path_hit_escaped((*path).hit);
        // No number is drawn in vacuum: a scene without media renders as it does without MEDIA.
        var u = 0.0;
        if ((*path).medium != VACUUM) {
            u = rng_f32(&rng);
        }
#if MEDIA_GRID
        // Delta tracking in a grid medium draws more numbers after `u` (shaders/lib/media_grid.wgsl).
        let flight = media_free_flight((*path).medium, (*path).origin, (*path).direction, select((*path).hit.t, INFINITE_DISTANCE, escaped), u, &rng);
#else
        let flight = medium_free_flight((*path).medium, select((*path).hit.t, INFINITE_DISTANCE, escaped), u);
#endif
        (*path).throughput *= flight.weight;
        if (flight.scattered) {
            (*path).hit.t = flight.t;
            (*path).vertex = VERTEX_MEDIUM;
            break;
        }
        if (escaped) {
            break;
        }
        let s = path_surface(*path);
        if (!material_is_null(s.material)) {
            break;
        }
        (*path).medium = medium_after(s.material, s.normal, (*path).direction, (*path).medium);
        let origin = offset_ray_origin(s.position, side_normal(s.normal, (*path).direction), s.extent);
        (*path).gap += length(origin - (*path).origin);
        (*path).origin = origin;
        count(COUNTER_RAYS_EXTENSION, 1u);
        (*path).hit = path_hit(trace_closest(origin, (*path).direction, INFINITE_DISTANCE));
        if (i + 1u == MEDIA_MAX_CROSSINGS) {
            (*path).throughput = vec3<f32>(0.0);
        }
    }
    (*path).rng = rng;
}
#endif
