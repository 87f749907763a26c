#if MEDIA
// A sub-path's free flight to its next vertex through participating media (MEDIA;
// docs/media.md), shared by camera paths (shaders/pt/flight.wgsl) and light sub-paths
// (shaders/lt/media.wgsl). In a homogeneous medium a free flight picks the distance by one
// channel's extinction and weights it by all three (shaders/lib/media.wgsl); in a grid medium
// (MEDIA_GRID) it is delta tracking (shaders/lib/media_grid.wgsl).

// A ray between two vertices of a sub-path, as it goes through media: where it starts, the
// closest hit traced for it, the medium it travels in, what it found (VERTEX_SURFACE at the
// hit or VERTEX_MEDIUM at hit.t in `medium`), the distance its origin moved past crossed
// boundaries (`gap`) and the sub-path's throughput.
struct MediaFlight {
    origin: vec3<f32>,
    direction: vec3<f32>,
    hit: PathHit,
    medium: i32,
    vertex: u32,
    gap: f32,
    throughput: vec3<f32>,
}

// After the closest hit of `f`'s ray was found: the free flight through its medium up to that
// hit. The ray scatters in the medium (VERTEX_MEDIUM at hit.t) or reaches the surface
// (VERTEX_SURFACE); an index-matched boundary there is crossed without a vertex and the ray
// traced on from its far side, in the medium beyond it (each trace counted as `counter`). The
// throughput takes each flight's weight; `gap` adds the distance the ray's origin moved, for
// MIS at the next vertex.
fn flight_through_media(f: ptr<function, MediaFlight>, rng: ptr<function, u32>, counter: u32) {
    (*f).vertex = VERTEX_SURFACE;
    for (var i = 0u; i < MEDIA_MAX_CROSSINGS; i++) {
        let escaped = path_hit_escaped((*f).hit);
        // No number is drawn in vacuum: a scene without media renders as it does without MEDIA.
        var u = 0.0;
        if ((*f).medium != VACUUM) {
            u = rng_f32(rng);
        }
#if MEDIA_GRID
        // Delta tracking in a grid medium draws more numbers after `u` (shaders/lib/media_grid.wgsl).
        let flight = media_free_flight((*f).medium, (*f).origin, (*f).direction, select((*f).hit.t, INFINITE_DISTANCE, escaped), u, rng);
#else
        let flight = medium_free_flight((*f).medium, select((*f).hit.t, INFINITE_DISTANCE, escaped), u);
#endif
        (*f).throughput *= flight.weight;
        if (flight.scattered) {
            (*f).hit.t = flight.t;
            (*f).vertex = VERTEX_MEDIUM;
            break;
        }
        if (escaped) {
            break;
        }
        let s = path_hit_surface((*f).hit, (*f).origin, (*f).direction);
        if (!material_is_null(s.material)) {
            break;
        }
        (*f).medium = medium_after(s.material, s.normal, (*f).direction, (*f).medium);
        let origin = offset_ray_origin(s.position, side_normal(s.normal, (*f).direction), s.extent);
        (*f).gap += length(origin - (*f).origin);
        (*f).origin = origin;
        count(counter, 1u);
        (*f).hit = path_hit(trace_closest(origin, (*f).direction, INFINITE_DISTANCE));
        if (i + 1u == MEDIA_MAX_CROSSINGS) {
            (*f).throughput = vec3<f32>(0.0);
        }
    }
}
#endif
