// Light emission: the first vertex and direction of a light sub-path, for every light kind,
// with the densities bidirectional MIS needs (SmallVCM's Emit / Illuminate / GetRadiance
// triple, our own code). Area lights emit cosine-weighted from a uniform point; point lights
// uniformly over the sphere; a directional light from a disk of the scene's bounding-sphere
// radius; the background from a uniform direction (an environment map from its own
// distribution) and a disk across the scene. Lights are picked by `pick_light` (lights.wgsl).
// Needs the resources of lights.wgsl.

// Density over a disk of radius r perpendicular to a direction (directional and background
// emission start on it).
fn disk_pdf(r: f32) -> f32 {
    return 1.0 / (PI * r * r);
}

// A uniform point on the unit disk (concentric mapping), as (x, y).
fn sample_unit_disk(u: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * u - vec2<f32>(1.0);
    if (a.x == 0.0 && a.y == 0.0) {
        return vec2<f32>(0.0);
    }
    var r: f32;
    var phi: f32;
    if (abs(a.x) > abs(a.y)) {
        r = a.x;
        phi = (PI / 4.0) * (a.y / a.x);
    } else {
        r = a.y;
        phi = PI / 2.0 - (PI / 4.0) * (a.x / a.y);
    }
    return r * vec2<f32>(cos(phi), sin(phi));
}

// An emitted ray. `radiance` is what leaves the light along the ray (radiance, a point
// light's intensity, a directional light's irradiance); `emission_pdf` the density of the
// (origin, direction) pair (area x solid angle); `direct_pdf` the density with which direct
// illumination picks the origin (area density; solid angle for the background; 1 for delta
// lights); `cos_light` the cosine at an area light (1 otherwise). Not including the pick
// probability. `radiance` is zero when the sample is void.
struct Emission {
    origin: vec3<f32>,
    direction: vec3<f32>,
    radiance: vec3<f32>,
    emission_pdf: f32,
    direct_pdf: f32,
    cos_light: f32,
    is_delta: bool,
    is_finite: bool,
}

fn emit_light(index: u32, u_point: vec2<f32>, u_direction: vec2<f32>) -> Emission {
    let l = lights[index];
    var e: Emission;
    e.radiance = l.radiance;
    e.cos_light = 1.0;
    e.is_delta = false;
    e.is_finite = true;
    switch l.kind {
        case LIGHT_AREA: {
            let bc = sample_uniform_triangle(u_point);
            let point = l.position + bc.x * l.e1 + bc.y * l.e2;
            let local = sample_cos_hemisphere(u_direction);
            e.direction = to_world(frame_from_z(l.normal), local);
            e.origin = offset_ray_origin(point, l.normal, triangle_extent(l.position, l.e1, l.e2));
            e.cos_light = local.z;
            e.direct_pdf = l.inv_area;
            e.emission_pdf = l.inv_area * local.z * INV_PI;
            if (local.z < EPS_COSINE) {
                e.radiance = vec3<f32>(0.0);
            }
        }
        case LIGHT_POINT, LIGHT_SPOT: {
            e.origin = l.position;
            e.direction = sample_uniform_sphere(u_direction);
            e.direct_pdf = 1.0;
            e.emission_pdf = UNIFORM_SPHERE_PDF;
            e.is_delta = true;
#if LIGHT_SPOT
            if (l.kind == LIGHT_SPOT) {
                e.radiance *= spot_falloff(l, e.direction);
            }
#endif
        }
        case LIGHT_DIRECTIONAL: {
            e.direction = l.position;
            let d = sample_unit_disk(u_point);
            let f = frame_from_z(e.direction);
            e.origin = scene.center + scene.radius * (f.t * d.x + f.b * d.y - e.direction);
            e.direct_pdf = 1.0;
            e.emission_pdf = disk_pdf(scene.radius);
            e.is_delta = true;
            e.is_finite = false;
        }
#if LIGHT_ENVIRONMENT
        case LIGHT_ENVIRONMENT: {
            // A direction towards the sky from the map's distribution, light travelling back.
            let sky = env_sample(u_direction);
            e.direction = -sky.direction;
            let d = sample_unit_disk(u_point);
            let f = frame_from_z(e.direction);
            e.origin = scene.center + scene.radius * (f.t * d.x + f.b * d.y - e.direction);
            e.radiance = select(vec3<f32>(0.0), l.radiance * sky.radiance, sky.pdf > 0.0);
            e.direct_pdf = sky.pdf;
            e.emission_pdf = sky.pdf * disk_pdf(scene.radius);
            e.is_finite = false;
        }
#endif
        default: {
            // The background: a uniform direction towards the sky, light travelling back.
            let towards = sample_uniform_sphere(u_direction);
            e.direction = -towards;
            let d = sample_unit_disk(u_point);
            let f = frame_from_z(e.direction);
            e.origin = scene.center + scene.radius * (f.t * d.x + f.b * d.y - e.direction);
            e.direct_pdf = UNIFORM_SPHERE_PDF;
            e.emission_pdf = UNIFORM_SPHERE_PDF * disk_pdf(scene.radius);
            e.is_finite = false;
        }
    }
    return e;
}

// For a direct-illumination sample `ill` of light `index` (from `illuminate`): the density
// with which `emit_light` would emit along it (x: area x solid angle) and the cosine at the
// light (y).
fn emission_pdf_of(index: u32, ill: Illumination) -> vec2<f32> {
    let l = lights[index];
    switch l.kind {
        case LIGHT_AREA: {
            let c = dot(l.normal, -ill.direction);
            return vec2<f32>(l.inv_area * max(c, 0.0) * INV_PI, c);
        }
        case LIGHT_POINT, LIGHT_SPOT: {
            return vec2<f32>(UNIFORM_SPHERE_PDF, 1.0);
        }
        case LIGHT_DIRECTIONAL: {
            return vec2<f32>(disk_pdf(scene.radius), 1.0);
        }
        case LIGHT_ENVIRONMENT: {
            return vec2<f32>(ill.pdf * disk_pdf(scene.radius), 1.0);
        }
        default: {
            return vec2<f32>(UNIFORM_SPHERE_PDF * disk_pdf(scene.radius), 1.0);
        }
    }
}
