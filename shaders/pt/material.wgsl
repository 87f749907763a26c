// Pass `material` (Loop, the material stage): next-event estimation (a shadow ray towards a
// light picked in proportion to its power) and the next direction from the BSDF, with Russian roulette. With
// the albedo roulette rule the BSDF densities used for MIS include the continuation
// probability, as in SmallVCM; with the throughput rule (Mitsuba's) they do not.
//
// The shadow ray is emitted last, once the path has moved on: where `shadow` runs in the same
// kernel it is traced at once, and the vertex's surface and BSDF are no longer held in
// registers during that traversal.

fn material(path: ptr<function, CameraPath>) -> bool {
#if MEDIA
    if ((*path).vertex == VERTEX_MEDIUM) {
        return material_in_medium(path);
    }
#endif
    let v = path_vertex_taken(*path);
    var rng = (*path).rng;
    let light_u = rng_f32(&rng);
    let light_uv = rng_vec2(&rng);
    let u = vec3<f32>(rng_vec2(&rng), rng_f32(&rng));
    let roulette_u = rng_f32(&rng);
    (*path).rng = rng;
    let shadow = material_next_event(*path, v, light_u, light_uv);
    let goes_on = material_scatter(path, v, u, roulette_u);
    if (!is_black(shadow.contribution)) {
        emit_shadow(shadow);
    }
    return goes_on;
}

// The surface and BSDF at the path's last hit: `logic`'s, when it ran just before in this
// thread (with textures; see `PathVertex`), else set up here.
fn path_vertex_taken(path: CameraPath) -> PathVertex {
#if TEXTURES
    if (path_vertex.valid) {
        path_vertex.valid = false;
        return path_vertex;
    }
#endif
    let s = path_surface(path);
    return PathVertex(s, surface_bsdf(s, -path.direction), false);
}

#if MEDIA
// The pass at a scattering in the path's medium: next-event estimation and a direction from
// the phase function (shaders/pt/medium_bounce.wgsl), the shadow ray emitted last as above.
fn material_in_medium(path: ptr<function, CameraPath>) -> bool {
    var rng = (*path).rng;
    let light_u = rng_f32(&rng);
    let light_uv = rng_vec2(&rng);
    let u = rng_vec2(&rng);
    let roulette_u = rng_f32(&rng);
    (*path).rng = rng;
    let shadow = medium_next_event(*path, light_u, light_uv);
    let goes_on = medium_scatter(path, u, roulette_u);
    if (!is_black(shadow.contribution)) {
        emit_shadow(shadow);
    }
    return goes_on;
}
#endif
