#if MEDIA
// A camera path's bounce at a scattering in a participating medium (MEDIA; docs/media.md), as
// functions of the random numbers they use, for pass `material` (shaders/pt/material.wgsl):
// next-event estimation through the media, weighted by MIS against phase sampling, and a
// direction from the phase function with Russian roulette. With the albedo roulette rule the
// path goes on with the medium's largest single-scattering albedo, and the phase densities used
// for MIS include that probability, as the BSDF densities do (shaders/pt/bounce.wgsl).

// The position of the path's scattering in its medium.
fn medium_vertex_position(path: CameraPath) -> vec3<f32> {
    return path.origin + path.hit.t * path.direction;
}

// The factor of the continuation probability in the phase densities used for MIS.
fn medium_mis_continuation(medium: Medium) -> f32 {
    return select(1.0, medium_continuation(medium), RR_ALBEDO);
}

// Next-event estimation at the path's scattering in its medium: a light picked with `light_u`,
// a point on it with `light_uv`, and the shadow ray from the scattering (black: none).
fn medium_next_event(path: CameraPath, light_u: f32, light_uv: vec2<f32>) -> ShadowRay {
    let none = ShadowRay();
    if (scene.num_lights == 0u) {
        return none;
    }
    let position = medium_vertex_position(path);
    let picked = pick_light(light_u);
    let ill = illuminate(picked.index, position, light_uv);
    if (is_black(ill.radiance)) {
        return none;
    }
    let medium = medium_at(path.medium);
    let f = phase_hg(medium.g, path.direction, ill.direction);
    var w = 1.0;
    if (!ill.is_delta) {
        w = mis_weight(ill.pdf * picked.probability, f * medium_mis_continuation(medium));
    }
    let contribution = path.throughput * ill.radiance * (f * w / (picked.probability * ill.pdf));
    return ShadowRay(position, path.pixel, ill.direction, light_shadow_distance(position, position, ill), contribution, path.medium);
}

// The path's next direction from the phase function at its scattering (sampled with `u`),
// then Russian roulette with `roulette_u`; false when the path ends.
fn medium_scatter(path: ptr<function, CameraPath>, u: vec2<f32>, roulette_u: f32) -> bool {
    let medium = medium_at((*path).medium);
    let direction = sample_phase_hg(medium.g, (*path).direction, u);
    var q = 1.0;
    if (RR_ALBEDO) {
        q = medium_continuation(medium);
    } else if ((*path).length >= RR_START) {
        q = min(max_component((*path).throughput), RR_MAX);
    }
    if (roulette_u >= q) {
        return false;
    }
    (*path).throughput /= q;
    (*path).last_pdf = phase_hg(medium.g, (*path).direction, direction) * medium_mis_continuation(medium);
    (*path).last_specular = 0u;
    (*path).origin = medium_vertex_position(*path);
    (*path).direction = direction;
    (*path).gap = 0.0;
    return true;
}
#endif
