// Pass `trace_make` (Start over PATHS): in a session's first frame only, the rays the cast
// passes trace every frame, three per index: the camera ray through a jittered point of a
// pixel (pixels in 8x8 tiles, as PT's), and at its hit an ambient-occlusion ray (length
// TRACE_AO_LENGTH times the scene's bounding radius) and a diffuse-bounce ray (unbounded),
// both cosine-distributed about the normal facing the camera. Later frames leave them. With
// TRACE_SORT it also keys the diffuse ray for `trace_sort` (below).

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
#if TRACE_SORT
    trace_keys[index] = trace_sort_key(diffuse);
    trace_order[index] = index;
#endif
    return false;
}

// With TRACE_SORT: a ray's sort key, its direction's octahedral code (5 bits an axis,
// interleaved) and its origin's cell in the scene's bounding cube (6 bits an axis, as a Morton
// code), direction first unless TRACE_SORT_ORIGIN_FIRST; a missing ray sorts last.
fn trace_sort_key(r: TraceRay) -> u32 {
    if (r.t_max <= 0.0) {
        return 0xffffffffu;
    }
    let cube = (r.origin - scene.center) / (2.0 * scene.radius) + 0.5;
    let c = vec3<u32>(clamp(cube * 64.0, vec3<f32>(0.0), vec3<f32>(63.0)));
    let origin = morton_code(c);
    let e = unpack2x16snorm(encode_octahedral(r.direction)) * 0.5 + 0.5;
    let d = vec2<u32>(clamp(e * 32.0, vec2<f32>(0.0), vec2<f32>(31.0)));
    let direction = morton_spread(d.x) | (morton_spread(d.y) << 1u);
    return select((direction << 18u) | origin, (origin << 14u) | direction, TRACE_SORT_ORIGIN_FIRST);
}
