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

#if BSDF_BECKMANN
// The isotropic Beckmann-Spizzichino distribution (Mitsuba's default), in the same local
// frame: D, Smith's Lambda for it (exact, through erf), and sampling of the normals visible
// from a direction: the stretched configuration's slope along the incident plane by
// inverting its CDF (Newton steps kept in a bracket), the other slope Gaussian, then rotated
// and stretched back (Heitz and d'Eon 2014). Masking, G2 and the visible pdf have the GGX
// functions' forms with this Lambda (`pbr_*` in bsdf.wgsl pick the distribution).

const INV_SQRT_PI: f32 = 0.5641895835;

// erf(x), Abramowitz and Stegun 7.1.26 (absolute error under 1.5e-7).
fn erf_approx(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * abs(x));
    let poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let e = 1.0 - poly * exp(-x * x);
    return select(-e, e, x >= 0.0);
}

// The inverse of erf on (-1, 1): Giles' single-precision approximation (2010), refined by
// one Newton step on `erf_approx` so that the two are each other's inverse.
fn erfinv_approx(y: f32) -> f32 {
    let x = clamp(y, -0.9999999, 0.9999999);
    var w = -log((1.0 - x) * (1.0 + x));
    var p: f32;
    if (w < 5.0) {
        w = w - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    let r = p * x;
    return r - (erf_approx(r) - x) / (2.0 * INV_SQRT_PI * exp(-r * r));
}

// Density of microfacet normals `h` (projected: integrates h.z D(h) to 1).
fn beckmann_d(h: vec3<f32>, alpha: f32) -> f32 {
    if (h.z <= 0.0) {
        return 0.0;
    }
    let c2 = h.z * h.z;
    let a2 = alpha * alpha;
    let tan2 = max(0.0, 1.0 - c2) / c2;
    return exp(-tan2 / a2) / (PI * a2 * c2 * c2);
}

// Smith's Lambda for direction `w`: (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), where
// a = 1 / (alpha tan theta).
fn beckmann_lambda(w: vec3<f32>, alpha: f32) -> f32 {
    let z2 = w.z * w.z;
    let sin2 = max(0.0, 1.0 - z2);
    if (sin2 <= 0.0) {
        return 0.0;
    }
    let a = sqrt(z2 / sin2) / alpha;
    return 0.5 * (erf_approx(a) - 1.0) + 0.5 * INV_SQRT_PI * exp(-a * a) / a;
}

// Walter et al.'s (2007) rational fit of Smith's masking for Beckmann (within 0.35% of it),
// with which Mitsuba evaluates its Beckmann BSDFs: a function of a = 1 / (alpha tan theta),
// 1 from a = 1.6 on.
fn beckmann_g1_fit(w: vec3<f32>, alpha: f32) -> f32 {
    let z2 = w.z * w.z;
    let sin2 = max(0.0, 1.0 - z2);
    if (sin2 <= 0.0) {
        return 1.0;
    }
    let a = sqrt(z2 / sin2) / alpha;
    if (a >= 1.6) {
        return 1.0;
    }
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

// The CDF (unnormalised) of the slope x along the incident plane of the normals visible from
// polar angle theta (cos c, sin s) on the unit Beckmann surface: the integral of
// (c - t s) exp(-t^2) / sqrt(pi) up to x.
fn beckmann_slope_cdf(x: f32, c: f32, s: f32) -> f32 {
    return 0.5 * c * (1.0 + erf_approx(x)) + 0.5 * INV_SQRT_PI * s * exp(-x * x);
}

// The visible slope along the incident plane for uniform `u`: the CDF inverted over
// (-6, cot theta] (the density is 0 beyond cot theta, negligible below -6).
fn beckmann_visible_slope(c: f32, s: f32, u: f32) -> f32 {
    if (s < 1e-4) {
        return erfinv_approx(2.0 * u - 1.0);
    }
    var lo = -6.0;
    var hi = min(c / s, 6.0);
    let goal = u * beckmann_slope_cdf(hi, c, s);
    var x = clamp(erfinv_approx(2.0 * u - 1.0), lo, hi);
    for (var i = 0u; i < 24u; i += 1u) {
        let f = beckmann_slope_cdf(x, c, s) - goal;
        if (f > 0.0) {
            hi = x;
        } else {
            lo = x;
        }
        let df = (c - x * s) * exp(-x * x) * INV_SQRT_PI;
        var next = x - f / df;
        if (!(next > lo && next < hi)) {
            next = 0.5 * (lo + hi);
        }
        if (abs(next - x) < 1e-7) {
            return next;
        }
        x = next;
    }
    return x;
}

// A microfacet normal visible from `w` (w.z > 0), with density G1(w) max(0, w.h) D(h) / w.z.
fn beckmann_sample_visible(w: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let v = normalize(vec3<f32>(alpha * w.x, alpha * w.y, w.z));
    let s = sqrt(max(0.0, 1.0 - v.z * v.z));
    let x = beckmann_visible_slope(v.z, s, u.x);
    let y = erfinv_approx(2.0 * u.y - 1.0);
    let along = select(vec2<f32>(1.0, 0.0), v.xy / s, s > 1e-7);
    let slope = alpha * vec2<f32>(along.x * x - along.y * y, along.y * x + along.x * y);
    return normalize(vec3<f32>(-slope.x, -slope.y, 1.0));
}
#endif
