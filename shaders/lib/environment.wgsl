// Environment maps: equirectangular radiance, filtered bilinearly (texel (i, j) at
// u = (i + 1/2) / w, and at v = (j + 1/2) / h, or v = j / (h - 1) when `pole_to_pole`; wrap in
// u, clamp in v), importance-sampled over the bilinear patches between the texels: a patch
// from a marginal CDF over the patch rows and a conditional one over the row's columns, both
// proportional to the mean of the corners' sampling weights x the patch's solid angle, then a
// point with density proportional to the bilinear weight. Needs the resources `environment`,
// `env_texels` (rgb radiance, sampling weight) and `env_cdf` (the rows' CDFs, the marginal
// CDF, the rows' densities); see scenes/src/environment.rs, whose CPU mirror this follows,
// for the layout and the convention: map space has +Y up at row 0, the image centre looks
// along -Z, u grows towards +X; world = rotation about +Y of map.
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

// The number of patch rows: height + 1 between the rows' centres (the outer two half a row
// high, clamped to the first and last rows), height - 1 (at least 1) from pole to pole.
fn env_patch_rows() -> u32 {
    let h = environment.height;
    return select(h + 1u, max(h, 2u) - 1u, environment.pole_to_pole != 0u);
}

// The v of patch row `r`'s top edge.
fn env_row_edge(r: u32) -> f32 {
    if (environment.pole_to_pole != 0u) {
        return f32(r) / f32(env_patch_rows());
    }
    return clamp((f32(r) - 0.5) / f32(environment.height), 0.0, 1.0);
}

// A point of the map in its bilinear patch.
struct EnvPatch {
    corners: vec4<u32>,     // texel indices: (col, top), (col + 1, top), (col, bottom), (col + 1, bottom)
    row: u32,               // the patch row
    st: vec2<f32>,          // the position in the patch, [0, 1]^2
}

// Patch (`row`, `col`) and the position `st` in it.
fn env_patch(row: u32, col: u32, st: vec2<f32>) -> EnvPatch {
    let w = environment.width;
    let last = environment.height - 1u;
    var top = min(max(row, 1u) - 1u, last);
    var bottom = min(row, last);
    if (environment.pole_to_pole != 0u) {
        top = min(row, last);
        bottom = min(row + 1u, last);
    }
    let next = select(col + 1u, 0u, col + 1u >= w);
    var p: EnvPatch;
    p.corners = vec4<u32>(top * w + col, top * w + next, bottom * w + col, bottom * w + next);
    p.row = row;
    p.st = st;
    return p;
}

// The patch holding image coordinates `uv`, and the position in it.
fn env_locate(uv: vec2<f32>) -> EnvPatch {
    let w = f32(environment.width);
    let x = fract(uv.x - 0.5 / w) * w;
    let col = min(u32(x), environment.width - 1u);
    let rows = env_patch_rows();
    let y = select(uv.y * f32(environment.height) + 0.5, uv.y * f32(rows), environment.pole_to_pole != 0u);
    let row = min(u32(max(y, 0.0)), rows - 1u);
    let v0 = env_row_edge(row);
    let t = clamp((uv.y - v0) / (env_row_edge(row + 1u) - v0), 0.0, 1.0);
    return env_patch(row, col, vec2<f32>(clamp(x - f32(col), 0.0, 1.0), t));
}

// The bilinear interpolation of four corners (ordered as EnvPatch's) at `st`; exact where
// the corners are equal.
fn env_bilerp(c00: vec4<f32>, c10: vec4<f32>, c01: vec4<f32>, c11: vec4<f32>, st: vec2<f32>) -> vec4<f32> {
    let top = c00 + (c10 - c00) * st.x;
    let bottom = c01 + (c11 - c01) * st.x;
    return top + (bottom - top) * st.y;
}

// The density over [0, 1]^2 with which `env_sample` picks a point of patch row `row` whose
// filtered sampling weight is `weight`.
fn env_pdf_uv(row: u32, weight: f32) -> f32 {
    let rows = env_patch_rows();
    return env_cdf[rows * (environment.width + 1u) + rows + 1u + row] * weight;
}

// Radiance (unscaled) towards which a world direction looks, and the solid-angle density
// with which `env_sample` picks that direction.
fn env_lookup(direction: vec3<f32>) -> vec4<f32> {
    let d = env_to_map(direction);
    // theta by atan2, not acos(d.y): acos loses digits near the poles, where the density
    // grows as 1 / sin(theta).
    let uv = vec2<f32>(0.5 + atan2(d.x, -d.z) * (0.5 * INV_PI), atan2(length(d.xz), d.y) * INV_PI);
    let p = env_locate(uv);
    let c = p.corners;
    let t = env_bilerp(env_texels[c.x], env_texels[c.y], env_texels[c.z], env_texels[c.w], p.st);
    // From the horizontal components: exact near the poles (where 1 - cos^2 loses digits),
    // as the density grows like 1 / sin theta there.
    let sin_theta = length(d.xz);
    if (sin_theta <= 0.0) {
        return vec4<f32>(t.xyz, 0.0);
    }
    return vec4<f32>(t.xyz, env_pdf_uv(p.row, t.w) / (2.0 * PI * PI * sin_theta));
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

// The inverse CDF at `u` of the density on [0, 1] proportional to (1 - x) a + x b (a, b
// non-negative; uniform when both are 0).
fn env_sample_linear(a: f32, b: f32, u: f32) -> f32 {
    let denominator = a + sqrt(a * a + (b * b - a * a) * u);
    return select(u, clamp(u * (a + b) / denominator, 0.0, 1.0), denominator > 0.0);
}

struct EnvironmentSample {
    direction: vec3<f32>,   // world
    pdf: f32,               // solid angle
    radiance: vec3<f32>,    // unscaled
}

// A direction with density proportional to the filtered map's luminance (within each
// patch; across patches to their mean luminance x solid angle).
fn env_sample(u: vec2<f32>) -> EnvironmentSample {
    let w = environment.width;
    let rows = env_patch_rows();
    let y = env_sample_cdf(rows * (w + 1u), rows, u.y);
    let row = min(u32(y), rows - 1u);
    let x = env_sample_cdf(row * (w + 1u), w, u.x);
    let col = min(u32(x), w - 1u);
    let corners = env_patch(row, col, vec2<f32>(0.0)).corners;
    let c00 = env_texels[corners.x];
    let c10 = env_texels[corners.y];
    let c01 = env_texels[corners.z];
    let c11 = env_texels[corners.w];
    // The point from the patch's bilinear density: v from its marginal, then u given v, each
    // from the position of `u` within the CDF step it fell in.
    let t = env_sample_linear(c00.w + c10.w, c01.w + c11.w, y - f32(row));
    let s = env_sample_linear(c00.w + (c01.w - c00.w) * t, c10.w + (c11.w - c10.w) * t, x - f32(col));
    let v0 = env_row_edge(row);
    let uv = vec2<f32>(fract((f32(col) + s + 0.5) / f32(w)), v0 + (env_row_edge(row + 1u) - v0) * t);
    let d = env_direction(uv);
    let texel = env_bilerp(c00, c10, c01, c11, vec2<f32>(s, t));
    var r: EnvironmentSample;
    r.direction = env_to_world(d.xyz);
    r.radiance = texel.xyz;
    r.pdf = select(0.0, env_pdf_uv(row, texel.w) / (2.0 * PI * PI * d.w), d.w > 0.0);
    return r;
}
#endif
