// Pass `light_bounce` (Loop): at the light sub-path's new vertex, the t = 1 connection to the
// camera (a shadow ray that splats into the pixel it projects to) and the next direction.

fn light_bounce(p: ptr<function, LightPath>) -> bool {
#if MEDIA
    if ((*p).vertex == VERTEX_MEDIUM) {
        return light_bounce_in_medium(p);
    }
#endif
    let a = light_path_land(p);
    if (!a.alive) {
        return false;
    }
    let s = a.s;
    let bsdf = a.bsdf;
    if (!bsdf.is_delta && (*p).length + 1u <= MAX_PATH_LENGTH) {
        var rng = (*p).rng;
        let lens = camera_lens_sample(&rng);
        (*p).rng = rng;
#if MEDIA
        var ray = light_vertex_to_camera(light_vertex_at(*p, s), bsdf, mis_counts(1.0), lens);
        // The shadow ray starts in the medium on the camera's side of the surface.
        ray.medium = medium_after(s.material, s.normal, ray.direction, (*p).medium);
#else
        let ray = light_vertex_to_camera(light_vertex_at(*p, s), bsdf, mis_counts(1.0), lens);
#endif
        if (!is_black(ray.contribution)) {
            emit_shadow(ray);
        }
    }
    if ((*p).length + 2u > MAX_PATH_LENGTH) {
        return false;
    }
    return light_path_scatter(p, s, bsdf, mis_counts(1.0));
}
