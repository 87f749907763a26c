#if MEDIA
// Light sub-paths through participating media (MEDIA; docs/media.md), for light tracing: a
// sub-path starts in the medium its light is in, flies freely through media (the flight of
// camera paths, shaders/common/flight.wgsl), scatters at medium vertices by the phase function
// and connects every vertex, surface and medium, to the camera through the `shadow` pass,
// whose ray carries the transmittance of the media it crosses. The MIS quantities (d_vcm,
// d_vc) are not carried through media: light tracing, the one graph of light sub-paths that
// handles media, weights every contribution 1 (LIGHT_TRACE_ONLY).

// The medium at the point `origin` of a light: along the segment from there to the camera, the
// medium on the near side of the first surface whose material bounds a medium; the camera's
// where no surface on the way does (surfaces that bound none leave a ray in its medium).
// A segment crossing more than MEDIA_MAX_CROSSINGS surfaces that bound none takes the camera's.
// In a scene without media (index-matched boundaries alone, or every feature compiled in) all
// is vacuum, and no ray is traced.
fn light_start_medium(origin: vec3<f32>) -> i32 {
    if (media_info.y == 0) {
        return VACUUM;
    }
    let to_camera = camera.position - origin;
    var left = length(to_camera);
    if (!(left > 0.0)) {
        return media_info.x;
    }
    let d = to_camera / left;
    var o = origin;
    for (var i = 0u; i < MEDIA_MAX_CROSSINGS; i++) {
        count(COUNTER_RAYS_LIGHT, 1u);
        let hit = trace_closest(o, d, left);
        if (!hit.found) {
            break;
        }
        let s = surface_at(hit, o, d);
        let sides = material_media[s.material];
        if (sides.x != VACUUM || sides.y != VACUUM) {
            return medium_after(s.material, s.normal, -d, VACUUM);
        }
        let next = offset_ray_origin(s.position, side_normal(s.normal, d), s.extent);
        left -= length(next - o);
        o = next;
        if (left <= 0.0) {
            break;
        }
    }
    return media_info.x;
}

// Puts a sub-path that `light_path_start_stratified` started into the medium of its light;
// false when it carries no light there. A light at infinity (the background, a directional
// light) sends nothing through a medium around the scene: its light crosses an infinite
// distance of it (the transmittance of a channel without extinction, 1, in the others 0), as
// a camera path sees it.
fn light_path_start_in_media(p: ptr<function, LightPath>) -> bool {
    (*p).medium = light_start_medium((*p).origin);
    (*p).vertex = VERTEX_SURFACE;
    if ((*p).is_finite == 0u && (*p).medium != VACUUM) {
        let clear = medium_at((*p).medium).sigma_t == vec3<f32>(0.0);
        (*p).throughput *= select(vec3<f32>(0.0), vec3<f32>(1.0), clear);
    }
    return !is_black((*p).throughput);
}

// After the sub-path's ray was traced: its free flight through media to its next vertex, a
// scattering in its medium (VERTEX_MEDIUM) or the surface hit beyond index-matched boundaries.
// The distance the ray's origin moves past boundaries (`gap`) is not kept: no MIS here.
fn light_path_through_media(p: ptr<function, LightPath>) {
    var rng = (*p).rng;
    var f = MediaFlight((*p).origin, (*p).direction, (*p).hit, (*p).medium, VERTEX_SURFACE, 0.0, (*p).throughput);
    flight_through_media(&f, &rng, COUNTER_RAYS_LIGHT);
    (*p).origin = f.origin;
    (*p).hit = f.hit;
    (*p).medium = f.medium;
    (*p).vertex = f.vertex;
    (*p).throughput = f.throughput;
    (*p).rng = rng;
}

// The t = 1 strategy at the sub-path's scattering at `position` in `medium`: the shadow ray
// towards the lens point of `lens` with the contribution to the pixel it projects to (zero
// where the camera cannot see the point). The phase function stands for the BSDF and there
// is no cosine at the vertex; the `shadow` pass multiplies the transmittance to the camera.
fn light_medium_vertex_to_camera(p: LightPath, medium: Medium, position: vec3<f32>, lens: vec2<f32>) -> ShadowRay {
    var ray = ShadowRay(position, 0u, vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), p.medium);
    let lens_point = camera_lens_point(lens);
    let raster = camera_raster(position, lens_point);
    if (raster.z <= 0.0) {
        return ray;
    }
    let to_camera = lens_point - position;
    let distance2 = dot(to_camera, to_camera);
    let distance = sqrt(distance2);
    let direction = to_camera / distance;
    // The density with which the camera picks this point, per unit area across the ray.
    let camera_pdf_a = camera_pdf_w(raster.z) / distance2;
    let f = phase_hg(medium.g, p.direction, direction);
    ray.pixel = min(u32(raster.y), u32(camera.height) - 1u) * WIDTH + min(u32(raster.x), WIDTH - 1u);
    ray.direction = direction;
    ray.distance = distance;
    ray.contribution = p.throughput * (f * camera_pdf_a / f32(PIXELS));
    return ray;
}

// Continues the sub-path from its scattering at `position` in `medium`: Russian roulette with
// the medium's largest single-scattering albedo (the albedo rule light sub-paths use on
// surfaces), then a direction from the phase function, whose weight is 1; false when it ends.
fn light_path_scatter_in_medium(p: ptr<function, LightPath>, medium: Medium, position: vec3<f32>) -> bool {
    var rng = (*p).rng;
    let u = rng_vec2(&rng);
    let roulette_u = rng_f32(&rng);
    (*p).rng = rng;
    let q = medium_continuation(medium);
    if (roulette_u >= q) {
        return false;
    }
    (*p).throughput /= q;
    (*p).origin = position;
    (*p).direction = sample_phase_hg(medium.g, (*p).direction, u);
    return true;
}

// Pass `light_bounce` at a scattering in the sub-path's medium: the camera connection, then
// the next direction (the lengths as at a surface vertex).
fn light_bounce_in_medium(p: ptr<function, LightPath>) -> bool {
    let medium = medium_at((*p).medium);
    let position = (*p).origin + (*p).hit.t * (*p).direction;
    if ((*p).length + 1u <= MAX_PATH_LENGTH) {
        var rng = (*p).rng;
        let lens = camera_lens_sample(&rng);
        (*p).rng = rng;
        let ray = light_medium_vertex_to_camera(*p, medium, position, lens);
        if (!is_black(ray.contribution)) {
            emit_shadow(ray);
        }
    }
    if ((*p).length + 2u > MAX_PATH_LENGTH) {
        return false;
    }
    return light_path_scatter_in_medium(p, medium, position);
}
#endif
