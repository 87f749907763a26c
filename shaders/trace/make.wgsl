// Pass `trace_make` (Start over PATHS): in a session's first frame only, the rays the cast
// passes trace every frame, three per index: the camera ray through a jittered point of a
// pixel (pixels in 8x8 tiles, as PT's), and at its hit an ambient-occlusion ray (length
// TRACE_AO_LENGTH times the scene's bounding radius) and a diffuse-bounce ray (unbounded),
// both cosine-distributed about the normal facing the camera. Later frames leave them.

fn trace_make(s: ptr<function, TraceItem>, index: u32) -> bool {
    if (frame.index != 0u) {
        return false;
    }
    let pixel = camera_tiled_pixel(index % PIXELS);
    var rng = rng_seed(frame.seed, 0u, index);
    let ray = camera_jittered_ray(pixel, &rng);
    trace_rays[index] = TraceRay(ray.origin, INFINITE_DISTANCE, ray.direction, pixel);
    var ao = TraceRay(ray.origin, 0.0, ray.direction, pixel);
    var diffuse = ao;
    let hit = trace_closest(ray.origin, ray.direction, INFINITE_DISTANCE);
    if (hit.found) {
        let surface = surface_at(hit, ray.origin, ray.direction);
        let n = select(-surface.normal, surface.normal, dot(surface.normal, ray.direction) < 0.0);
        let origin = offset_ray_origin(surface.position, n, surface.extent);
        let basis = frame_from_z(n);
        let ao_direction = to_world(basis, sample_cos_hemisphere(rng_vec2(&rng)));
        ao = TraceRay(origin, TRACE_AO_LENGTH * scene.radius, ao_direction, pixel);
        diffuse = TraceRay(origin, INFINITE_DISTANCE, to_world(basis, sample_cos_hemisphere(rng_vec2(&rng))), pixel);
    }
    trace_rays[PATHS + index] = ao;
    trace_rays[2u * PATHS + index] = diffuse;
    return false;
}
