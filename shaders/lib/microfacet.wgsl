// The isotropic GGX (Trowbridge-Reitz) microfacet distribution in a local frame whose +z is
// the macro-surface normal: the distribution of normals D, Smith's Lambda and masking G1,
// height-correlated masking-shadowing G2 = 1 / (1 + Lambda(o) + Lambda(i)) (Heitz 2014),
// sampling of the normals visible from a direction (Heitz 2018) with its density, and
// Schlick's Fresnel approximation for metals. `alpha` is GGX's roughness parameter.
#if BSDF_PBR
// Density of microfacet normals `h` (per unit solid angle of h, projected: integrates
// h.z D(h) to 1 over the upper hemisphere).
fn ggx_d(h: vec3<f32>, alpha: f32) -> f32 {
    if (h.z <= 0.0) {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = h.z * h.z * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

// Smith's Lambda for direction `w`: (sqrt(1 + alpha^2 tan^2) - 1) / 2.
fn ggx_lambda(w: vec3<f32>, alpha: f32) -> f32 {
    let z2 = w.z * w.z;
    let tan2 = max(0.0, 1.0 - z2) / max(z2, 1e-12);
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

// Masking of direction `w`.
fn ggx_g1(w: vec3<f32>, alpha: f32) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

// Height-correlated masking-shadowing of the pair `o`, `i` (either side of the surface).
fn ggx_g2(o: vec3<f32>, i: vec3<f32>, alpha: f32) -> f32 {
    return 1.0 / (1.0 + ggx_lambda(o, alpha) + ggx_lambda(i, alpha));
}

// Density of sampling the microfacet normal `h` with `ggx_sample_visible` from `w` (w.z > 0):
// G1(w) max(0, w.h) D(h) / w.z.
fn ggx_visible_pdf(w: vec3<f32>, h: vec3<f32>, alpha: f32) -> f32 {
    let wh = dot(w, h);
    if (wh <= 0.0 || w.z <= 0.0) {
        return 0.0;
    }
    return ggx_g1(w, alpha) * wh * ggx_d(h, alpha) / w.z;
}

// A microfacet normal visible from `w` (w.z > 0), with density `ggx_visible_pdf`: the
// hemisphere configuration is stretched to alpha = 1, where the visible normals are those
// of a hemisphere seen from the stretched direction: a uniform point on the disk facing it,
// its lower part squeezed into the visible half, lifted onto the hemisphere, stretched back.
fn ggx_sample_visible(w: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let v = normalize(vec3<f32>(alpha * w.x, alpha * w.y, w.z));
    let len2 = v.x * v.x + v.y * v.y;
    let t1 = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(-v.y, v.x, 0.0) / sqrt(len2), len2 > 1e-14);
    let t2 = cross(v, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + v.z);
    let p2 = mix(sqrt(max(0.0, 1.0 - p1 * p1)), r * sin(phi), s);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * v;
    return normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(1e-7, nh.z)));
}

// Schlick's approximation of a conductor's Fresnel reflectance with normal reflectance f0.
fn fresnel_schlick(f0: vec3<f32>, cos_theta: f32) -> vec3<f32> {
    let m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    let m2 = m * m;
    return f0 + (vec3<f32>(1.0) - f0) * (m2 * m2 * m);
}
#endif
