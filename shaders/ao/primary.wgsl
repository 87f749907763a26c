// Pass `ao_primary` (Start over PATHS): the camera ray of sample `index`; at its hit, one
// occlusion ray in a cosine-distributed direction about the normal facing the camera.

fn ao_primary(s: ptr<function, AoSample>, index: u32) -> bool {
    let pixel = index % PIXELS;
    (*s).pixel = pixel;
    var rng = rng_seed(frame.seed, frame.index, index);
    let ray = camera_jittered_ray(pixel, &rng);
    let d = ray.direction;
    count(COUNTER_RAYS_PRIMARY, 1u);
    let hit = trace_closest(ray.origin, d, INFINITE_DISTANCE);
    if (!hit.found) {
        return false;
    }
    let surface = surface_at(hit, ray.origin, d);
    let n = select(-surface.normal, surface.normal, dot(surface.normal, d) < 0.0);
    let direction = to_world(frame_from_z(n), sample_cos_hemisphere(rng_vec2(&rng)));
    emit_occlusion(OcclusionRay(offset_ray_origin(surface.position, n, surface.extent), pixel, direction));
    return false;
}
