#if MEDIA
// A camera path's free flight to its next vertex through participating media (MEDIA;
// docs/media.md), for pass `trace` (the flight itself: shaders/common/flight.wgsl).

// After `trace` found the closest hit of the path's ray: the free flight through the path's
// medium up to that hit (`flight_through_media`). The path scatters in the medium
// (VERTEX_MEDIUM at hit.t) or reaches the surface (VERTEX_SURFACE), past index-matched
// boundaries; `gap` adds the distance the ray's origin moved, for MIS at a light it hits.
fn path_through_media(path: ptr<function, CameraPath>) {
    var rng = (*path).rng;
    var f = MediaFlight((*path).origin, (*path).direction, (*path).hit, (*path).medium, VERTEX_SURFACE, (*path).gap, (*path).throughput);
    flight_through_media(&f, &rng, COUNTER_RAYS_EXTENSION);
    (*path).origin = f.origin;
    (*path).hit = f.hit;
    (*path).medium = f.medium;
    (*path).vertex = f.vertex;
    (*path).gap = f.gap;
    (*path).throughput = f.throughput;
    (*path).rng = rng;
}
#endif
