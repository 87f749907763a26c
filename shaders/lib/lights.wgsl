// Lights: sampling a point or direction for next-event estimation, and the radiance a path
// finds when it hits an area light or escapes to the background. Lights are picked
// uniformly. Needs the resources `lights` and `scene`.

struct Illumination {
    radiance: vec3<f32>,
    direction: vec3<f32>,       // unit, towards the light
    distance: f32,
    pdf: f32,                   // solid angle density (for delta lights, the geometry term's inverse)
    is_delta: bool,
    point: vec3<f32>,           // area lights: the sampled point
    normal: vec3<f32>,          // area lights: the light's normal
}

fn light_pick_probability() -> f32 {
    return 1.0 / f32(scene.num_lights);
}

fn illuminate(index: u32, p: vec3<f32>, u: vec2<f32>) -> Illumination {
    let l = lights[index];
    var r: Illumination;
    r.radiance = vec3<f32>(0.0);
    r.is_delta = false;
    switch l.kind {
        case LIGHT_AREA: {
            let bc = sample_uniform_triangle(u);
            r.point = l.position + bc.x * l.e1 + bc.y * l.e2;
            r.normal = l.normal;
            let to_light = r.point - p;
            let dist2 = dot(to_light, to_light);
            r.distance = sqrt(dist2);
            r.direction = to_light / r.distance;
            let cos_light = dot(l.normal, -r.direction);
            if (cos_light < EPS_COSINE) {
                return r;
            }
            r.pdf = l.inv_area * dist2 / cos_light;
            r.radiance = l.radiance;
        }
        case LIGHT_POINT: {
            let to_light = l.position - p;
            let dist2 = dot(to_light, to_light);
            r.distance = sqrt(dist2);
            r.direction = to_light / r.distance;
            r.pdf = dist2;
            r.is_delta = true;
            r.radiance = l.radiance;
        }
        case LIGHT_DIRECTIONAL: {
            r.direction = -l.position;
            r.distance = INFINITE_DISTANCE;
            r.pdf = 1.0;
            r.is_delta = true;
            r.radiance = l.radiance;
        }
        default: {
            r.direction = sample_uniform_sphere(u);
            r.distance = INFINITE_DISTANCE;
            r.pdf = UNIFORM_SPHERE_PDF;
            r.radiance = l.radiance;
        }
    }
    return r;
}

// Radiance leaving area light `index` towards -direction, and the area density with which
// `illuminate` picks the point (0 radiance on the back side).
fn area_light_radiance(index: u32, direction: vec3<f32>) -> vec4<f32> {
    let l = lights[index];
    if (dot(l.normal, -direction) <= 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(l.radiance, l.inv_area);
}

// Background radiance and the solid angle density of sampling that direction.
fn background_radiance() -> vec4<f32> {
    if (scene.background < 0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(lights[u32(scene.background)].radiance, UNIFORM_SPHERE_PDF);
}
