// Lights: sampling a point or direction for next-event estimation, and the radiance a path
// finds when it hits an area light or escapes to the background. Lights are picked in
// proportion to their estimated power through an alias table (`pick_light`; `light_pmf`
// gives the probability for MIS). Needs the resources `lights`, `light_alias`, `scene` and
// those of environment.wgsl.

struct Illumination {
    radiance: vec3<f32>,
    direction: vec3<f32>,       // unit, towards the light
    distance: f32,
    pdf: f32,                   // solid angle density (for delta lights, the geometry term's inverse)
    is_delta: bool,
    point: vec3<f32>,           // area lights: the sampled point
    normal: vec3<f32>,          // area lights: the light's normal
}

struct LightPick {
    index: u32,
    probability: f32,
}

// Picks a light (the scene has at least one) with probability proportional to its power,
// from 24 bits of one uniform number: the top ones pick one of the alias table's slots (the
// lights padded to a power of two), the others whether the slot keeps its own light or gives
// its other light. Each light is picked for a whole number of the 2^24 values, and that number
// over 2^24 is its `pmf`, exactly (scenes/src/alias.rs).
fn pick_light(u: f32) -> LightPick {
    let bits = min(u32(u * 16777216.0), 16777215u);
    let shift = countLeadingZeros(scene.num_lights - 1u) - 8u;
    let slot = bits >> shift;
    let entry = light_alias[slot];
    let index = select(entry.other, slot, (bits & ((1u << shift) - 1u)) < entry.keep);
    return LightPick(index, light_alias[index].pmf);
}

// The probability with which `pick_light` picks light `index`.
fn light_pmf(index: u32) -> f32 {
    return light_alias[index].pmf;
}

#if LIGHT_SPOT
// A spot's falloff towards unit direction `d` (travelling away from the light): 1 inside the
// inner cone, 0 outside the outer one; between them glTF's square of the linear ramp in
// cos theta, or (e2.x = 1) Mitsuba's ramp linear in the angle.
fn spot_falloff(l: Light, d: vec3<f32>) -> f32 {
    let c = dot(l.e1, d);
    if (c >= l.cos_inner) {
        return 1.0;
    }
    if (c <= l.cos_outer) {
        return 0.0;
    }
    if (l.e2.x != 0.0) {
        let outer = acos(l.cos_outer);
        return (outer - acos(c)) / (outer - acos(l.cos_inner));
    }
    let t = (c - l.cos_outer) / (l.cos_inner - l.cos_outer);
    return t * t;
}
#endif

fn illuminate(index: u32, p: vec3<f32>, u: vec2<f32>) -> Illumination {
    let l = lights[index];
    var r: Illumination;
    r.radiance = vec3<f32>(0.0);
    r.is_delta = false;
    switch l.kind {
#if LIGHT_AREA
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
#endif
#if LIGHT_PUNCTUAL
        case LIGHT_POINT, LIGHT_SPOT: {
            let to_light = l.position - p;
            let dist2 = dot(to_light, to_light);
            r.distance = sqrt(dist2);
            r.direction = to_light / r.distance;
            r.pdf = dist2;
            r.is_delta = true;
            r.radiance = l.radiance;
#if LIGHT_SPOT
            if (l.kind == LIGHT_SPOT) {
                r.radiance *= spot_falloff(l, -r.direction);
            }
#endif
        }
#endif
#if LIGHT_DIRECTIONAL
        case LIGHT_DIRECTIONAL: {
            r.direction = -l.position;
            r.distance = INFINITE_DISTANCE;
            r.pdf = 1.0;
            r.is_delta = true;
            r.radiance = l.radiance;
        }
#endif
#if LIGHT_ENVIRONMENT
        case LIGHT_ENVIRONMENT: {
            let e = env_sample(u);
            r.direction = e.direction;
            r.distance = INFINITE_DISTANCE;
            r.pdf = e.pdf;
            r.radiance = select(vec3<f32>(0.0), l.radiance * e.radiance, e.pdf > 0.0);
        }
#endif
#if LIGHT_BACKGROUND
        case LIGHT_BACKGROUND: {
            r.direction = sample_uniform_sphere(u);
            r.distance = INFINITE_DISTANCE;
            r.pdf = UNIFORM_SPHERE_PDF;
            r.radiance = l.radiance;
        }
#endif
        default: {}
    }
    return r;
}

// The length of the shadow ray from `origin` (offset from the shading point `p`) towards the
// light sample `ill` taken at `p`: to the sampled point, or unbounded for lights at infinity.
fn light_shadow_distance(p: vec3<f32>, origin: vec3<f32>, ill: Illumination) -> f32 {
    if (ill.distance >= INFINITE_DISTANCE) {
        return INFINITE_DISTANCE;
    }
    return shadow_distance(origin, p + ill.direction * ill.distance);
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

// The background's (constant or environment map) radiance towards `direction` (unit, away
// from the scene), and the solid angle density with which `illuminate` samples that
// direction (not counting the pick).
fn background_radiance(direction: vec3<f32>) -> vec4<f32> {
    if (scene.background < 0) {
        return vec4<f32>(0.0);
    }
    let l = lights[u32(scene.background)];
#if LIGHT_ENVIRONMENT
    if (l.kind == LIGHT_ENVIRONMENT) {
        let e = env_lookup(direction);
        return vec4<f32>(l.radiance * e.xyz, e.w);
    }
#endif
    return vec4<f32>(l.radiance, UNIFORM_SPHERE_PDF);
}
