// Pass `aov_sample` (Start over PATHS): sample `index`'s camera ray (path tracing's jitter)
// followed through delta surfaces to its first non-specular hit, where the quantity AOV_KIND
// goes to the film:
//   0 albedo: the material's diffuse reflectance, or its base colour (glTF), textures applied;
//   1 normal: the world-space shading normal on the side the ray arrived from, encoded as
//     (n + 1) / 2;
//   2 depth: (distance travelled from the camera, 1, 0): the path length to the hit (the ray's
//     length for a direct hit) and the coverage;
//   3 position: the world position minus (scene centre - scene radius), non-negative.
// A sample that escapes, or is lost in delta bounces, adds nothing.

struct AovSample {
    pixel: u32,
}

fn aov_sample(s: ptr<function, AovSample>, index: u32) -> bool {
    let pixel = index % PIXELS;
    (*s).pixel = pixel;
    var rng = rng_seed(frame.seed, frame.index, index);
    var origin = camera.position;
    var direction = camera_jittered_direction(pixel, &rng);
    var travelled = 0.0;
    for (var bounce = 0u; bounce < MAX_PATH_LENGTH; bounce += 1u) {
        count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, bounce == 0u), 1u);
        let hit = trace_closest(origin, direction, INFINITE_DISTANCE);
        if (!hit.found) {
            return false;
        }
        let surface = surface_at(hit, origin, direction);
        travelled += hit.t;
        let m = material_at(surface.material, surface.tex);
        let bsdf = bsdf_setup(m, surface.normal, surface.shading_normal, -direction);
        if (!bsdf.valid) {
            return false;
        }
        if (!bsdf.is_delta) {
            film_add(pixel, aov_value(m, surface, direction, travelled));
            return false;
        }
        let smp = bsdf_sample(bsdf, vec3<f32>(rng_vec2(&rng), rng_f32(&rng)));
        if (is_black(smp.f)) {
            return false;
        }
        let side = select(-surface.normal, surface.normal, dot(surface.normal, smp.direction) > 0.0);
        origin = offset_ray_origin(surface.position, side, surface.extent);
        direction = smp.direction;
    }
    return false;
}

// The film value of AOV_KIND at `surface`, reached along `direction` after `travelled`.
fn aov_value(m: Material, surface: Surface, direction: vec3<f32>, travelled: f32) -> vec3<f32> {
    switch AOV_KIND {
        case 0u: {
            return m.diffuse;
        }
        case 1u: {
            let n = select(-surface.shading_normal, surface.shading_normal, dot(surface.normal, direction) < 0.0);
            return 0.5 * (n + vec3<f32>(1.0));
        }
        case 2u: {
            return vec3<f32>(travelled, 1.0, 0.0);
        }
        default: {
            return surface.position - (scene.center - vec3<f32>(scene.radius));
        }
    }
}
