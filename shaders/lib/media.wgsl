#if MEDIA
// Participating media (MEDIA; docs/media.md): free-flight sampling and transmittance in
// homogeneous media, Henyey-Greenstein phase functions (isotropic: g = 0), and the media on
// either side of a surface. The media's data is in shaders/lib/scene.wgsl.

// No medium: vacuum.
const VACUUM: i32 = -1;
// The most index-matched boundaries one ray crosses between two vertices (a path that would
// cross more ends there).
const MEDIA_MAX_CROSSINGS: u32 = 64u;

// Medium `m` of the `media` buffer, which holds each as two vec4s.
fn medium_at(m: i32) -> Medium {
    let a = media[2 * m];
    let b = media[2 * m + 1];
    return Medium(a.xyz, a.w, b.xyz, bitcast<u32>(b.w));
}

// Whether a surface of `material` is an index-matched (`null`) boundary, crossed without a
// vertex.
fn material_is_null(material: u32) -> bool {
    return (materials[material].flags & MATERIAL_NULL) != 0u;
}

// The medium a ray along `d` travels in after crossing (or scattering at) a surface of
// `material` with geometric normal `n`, coming from `current`: the interior when it goes
// against the normal, the exterior otherwise; `current` where the surface bounds no media.
fn medium_after(material: u32, n: vec3<f32>, d: vec3<f32>, current: i32) -> i32 {
    let sides = material_media[material];
    if (sides.x == VACUUM && sides.y == VACUUM) {
        return current;
    }
    return select(sides.y, sides.x, dot(n, d) < 0.0);
}

// Transmittance along `t` of medium `m` (vacuum: 1), per channel.
fn medium_transmittance(m: i32, t: f32) -> vec3<f32> {
    if (m == VACUUM) {
        return vec3<f32>(1.0);
    }
    return exp(-medium_at(m).sigma_t * t);
}

// A free flight through medium `m` from a ray's origin towards a surface at distance
// `t_surface` (INFINITE_DISTANCE: none): where the ray scatters (`scattered`, at distance
// `t`) or that it reached the surface, and the factor of the path's throughput: transmittance
// (times the scattering coefficient where it scattered) over the density of the event. The
// distance is sampled by the extinction of a channel picked uniformly, and the density is the
// mean of the three channels' (one-sample MIS over the channels), so chromatic media stay
// unbiased with finite weights.
struct FreeFlight {
    t: f32,
    scattered: bool,
    weight: vec3<f32>,
}

fn medium_free_flight(m: i32, t_surface: f32, u: f32) -> FreeFlight {
    if (m == VACUUM) {
        return FreeFlight(t_surface, false, vec3<f32>(1.0));
    }
    let medium = medium_at(m);
    let scaled = 3.0 * u;
    let channel = min(u32(scaled), 2u);
    let sigma = medium.sigma_t[channel];
    let t = -log(max(1.0 - (scaled - f32(channel)), 1e-30)) / sigma;
    if (t < t_surface) {
        let tr = exp(-medium.sigma_t * t);
        let pdf = dot(medium.sigma_t * tr, vec3<f32>(1.0 / 3.0));
        return FreeFlight(t, true, select(vec3<f32>(0.0), medium.sigma_s * tr / pdf, pdf > 0.0));
    }
    let tr = exp(-medium.sigma_t * t_surface);
    let p = dot(tr, vec3<f32>(1.0 / 3.0));
    return FreeFlight(t_surface, false, select(vec3<f32>(0.0), tr / p, p > 0.0));
}

// The probability that a path goes on after scattering in `medium` with the albedo
// roulette rule: the largest single-scattering albedo.
fn medium_continuation(medium: Medium) -> f32 {
    return clamp(max_component(medium.sigma_s / max(medium.sigma_t, vec3<f32>(1e-30))), 0.0, 1.0);
}

// Henyey and Greenstein's phase function of mean cosine `g` for travel directions `d_in`
// (arriving) and `d_out` (leaving), per steradian; also the density of sampling `d_out`.
fn phase_hg(g: f32, d_in: vec3<f32>, d_out: vec3<f32>) -> f32 {
    let c = dot(d_in, d_out);
    let denom = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(max(denom, 1e-30)));
}

// A travel direction leaving a scattering in a medium of mean cosine `g`, sampled from the
// phase function around the arriving direction `d_in`.
fn sample_phase_hg(g: f32, d_in: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    var c = 1.0 - 2.0 * u.x;
    if (abs(g) > 1e-3) {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        c = clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    }
    let sin_theta = sqrt(max(0.0, 1.0 - c * c));
    let phi = 2.0 * PI * u.y;
    return to_world(frame_from_z(d_in), vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, c));
}

// The transmittance of a shadow ray from `origin` along `d` for `distance` that starts in
// medium `m`, through index-matched boundaries (crossed, changing media) and media (estimated
// by ratio tracking in grid media, MEDIA_GRID); zero where any other surface blocks it. At most MEDIA_MAX_CROSSINGS boundaries are crossed.
fn media_shadow_transmittance(origin: vec3<f32>, d: vec3<f32>, distance: f32, m: i32) -> vec3<f32> {
    var o = origin;
    var left = distance;
    var medium = m;
    var tr = vec3<f32>(1.0);
#if MEDIA_GRID
    var rng = grid_shadow_rng(origin, d, distance);
#endif
    for (var i = 0u; i < MEDIA_MAX_CROSSINGS; i++) {
        let hit = trace_closest(o, d, left);
        if (!hit.found) {
#if MEDIA_GRID
            return tr * media_transmittance(medium, o, d, left, &rng);
#else
            return tr * medium_transmittance(medium, left);
#endif
        }
        let s = surface_at(hit, o, d);
        if (!material_is_null(s.material)) {
            return vec3<f32>(0.0);
        }
#if MEDIA_GRID
        tr *= media_transmittance(medium, o, d, hit.t, &rng);
#else
        tr *= medium_transmittance(medium, hit.t);
#endif
        medium = medium_after(s.material, s.normal, d, medium);
        let next = offset_ray_origin(s.position, side_normal(s.normal, d), s.extent);
        left -= length(next - o);
        o = next;
        if (left <= 0.0 || is_black(tr)) {
            return tr;
        }
    }
    return vec3<f32>(0.0);
}
#endif
