// Environment maps: equirectangular radiance, importance-sampled by a 2D piecewise-constant
// distribution (marginal over rows, conditional over columns, proportional to luminance x
// sin theta). Needs the resources `environment`, `env_texels` and `env_cdf` (see
// scenes/src/environment.rs for the layout and the convention: map space has +Y up at row 0,
// the image centre looks along -Z, u grows towards +X; world = rotation about +Y of map).
#if LIGHT_ENVIRONMENT
// The map-space direction of image coordinates `uv` in [0, 1]^2, and sin theta.
fn env_direction(uv: vec2<f32>) -> vec4<f32> {
    let theta = PI * uv.y;
    let phi = 2.0 * PI * (uv.x - 0.5);
    let s = sin(theta);
    return vec4<f32>(s * sin(phi), cos(theta), -s * cos(phi), s);
}

fn env_to_world(d: vec3<f32>) -> vec3<f32> {
    let c = environment.cos_rotation;
    let s = environment.sin_rotation;
    return vec3<f32>(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

fn env_to_map(d: vec3<f32>) -> vec3<f32> {
    let c = environment.cos_rotation;
    let s = environment.sin_rotation;
    return vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

// The texel index containing image coordinates `uv`.
fn env_texel_index(uv: vec2<f32>) -> u32 {
    let col = min(u32(max(uv.x, 0.0) * f32(environment.width)), environment.width - 1u);
    let row = min(u32(max(uv.y, 0.0) * f32(environment.height)), environment.height - 1u);
    return row * environment.width + col;
}

// Radiance (unscaled) towards which a world direction looks, and the solid-angle density
// with which `env_sample` picks that direction.
fn env_lookup(direction: vec3<f32>) -> vec4<f32> {
    let d = env_to_map(direction);
    let uv = vec2<f32>(0.5 + atan2(d.x, -d.z) * (0.5 * INV_PI), acos(clamp(d.y, -1.0, 1.0)) * INV_PI);
    let t = env_texels[env_texel_index(uv)];
    // From the horizontal components: exact near the poles (where 1 - cos^2 loses digits),
    // as the density grows like 1 / sin theta there.
    let sin_theta = length(d.xz);
    if (sin_theta <= 0.0) {
        return vec4<f32>(t.xyz, 0.0);
    }
    return vec4<f32>(t.xyz, t.w / (2.0 * PI * PI * sin_theta));
}

// Samples the CDF of `count` intervals stored from `offset` in env_cdf: the continuous
// position in [0, count) whose CDF value is `u`.
fn env_sample_cdf(offset: u32, count: u32, u: f32) -> f32 {
    var lo = 0u;
    var hi = count;
    // Invariant: env_cdf[offset + lo] <= u < env_cdf[offset + hi] (the last value is 1).
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (env_cdf[offset + mid] <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let a = env_cdf[offset + lo];
    let b = env_cdf[offset + lo + 1u];
    let du = select(0.0, (u - a) / (b - a), b > a);
    return f32(lo) + clamp(du, 0.0, 0.99999994);
}

struct EnvironmentSample {
    direction: vec3<f32>,   // world
    pdf: f32,               // solid angle
    radiance: vec3<f32>,    // unscaled
}

// A direction with density proportional to the map's luminance.
fn env_sample(u: vec2<f32>) -> EnvironmentSample {
    let w = environment.width;
    let h = environment.height;
    let y = env_sample_cdf(h * (w + 1u), h, u.y);
    let row = min(u32(y), h - 1u);
    let x = env_sample_cdf(row * (w + 1u), w, u.x);
    let uv = vec2<f32>(x / f32(w), y / f32(h));
    let d = env_direction(uv);
    let t = env_texels[row * w + min(u32(x), w - 1u)];
    var r: EnvironmentSample;
    r.direction = env_to_world(d.xyz);
    r.radiance = t.xyz;
    r.pdf = select(0.0, t.w / (2.0 * PI * PI * d.w), d.w > 0.0);
    return r;
}
#endif
