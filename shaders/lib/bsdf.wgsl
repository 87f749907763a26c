// The Cornell-set BSDF (SmallVCM's model): a Lambertian lobe, a Phong lobe, and a mirror or
// smooth dielectric lobe, one lobe picked per sample in proportion to its albedo estimate.
// Directions in the local frame have the geometric normal as +z. `fix` is the direction
// towards the previous path vertex; `gen` the one generated or evaluated. Radiance (camera)
// paths scale refraction by eta^2. Works on a material resolved at the surface point
// (`material_at`).

const EPS_PHONG: f32 = 1e-3;

struct Bsdf {
    frame: Frame3,
    fix: vec3<f32>,             // local direction towards the previous vertex
    m: Material,
    diffuse_prob: f32,
    phong_prob: f32,
    reflect_prob: f32,
    refract_prob: f32,
    continuation: f32,          // Russian roulette continuation probability (albedo bound)
    fresnel: f32,
    cos_t: f32,                 // cosine of the refracted direction (0: none)
    is_delta: bool,
    valid: bool,
    adjoint: bool,              // importance (light) path: refraction without the eta^2 radiance scaling
}

// Fresnel reflectance of a smooth dielectric, unpolarised, and the cosine of the refracted
// direction (0 under total internal reflection); `ior` < 0 means a perfect mirror. Both come
// from one computation of sin^2 of the refraction angle, so that the reflectance and the
// sampling of refraction agree on where total internal reflection begins.
fn fresnel_dielectric(cos_incident: f32, ior: f32) -> vec2<f32> {
    if (ior < 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    var cos_i = cos_incident;
    var eta = 1.0 / ior;
    if (cos_i < 0.0) {
        cos_i = -cos_i;
        eta = ior;
    }
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if (sin_t2 >= 1.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let cos_t = sqrt(max(0.0, 1.0 - sin_t2));
    let r_parallel = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_perpendicular = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return vec2<f32>(0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular), cos_t);
}

fn bsdf_setup(m: Material, normal: vec3<f32>, towards_previous: vec3<f32>) -> Bsdf {
    var b: Bsdf;
    // A two-sided material scatters on the side the path arrives from.
    let two_sided = (m.flags & MATERIAL_TWO_SIDED) != 0u;
    let n = select(normal, -normal, two_sided && dot(normal, towards_previous) < 0.0);
    b.frame = frame_from_z(n);
    b.fix = to_local(b.frame, towards_previous);
    b.m = m;
    b.adjoint = false;
    b.valid = abs(b.fix.z) >= EPS_COSINE;
    if (!b.valid) {
        return b;
    }
    let fresnel = fresnel_dielectric(b.fix.z, m.ior);
    b.fresnel = fresnel.x;
    b.cos_t = fresnel.y;
    let albedo_diffuse = luminance(m.diffuse);
    let albedo_phong = luminance(m.phong);
    let albedo_reflect = b.fresnel * luminance(m.mirror);
    let albedo_refract = select(0.0, 1.0 - b.fresnel, m.ior > 0.0);
    let total = albedo_diffuse + albedo_phong + albedo_reflect + albedo_refract;
    if (total < 1e-9) {
        b.continuation = 0.0;
        b.is_delta = false;
        return b;
    }
    b.diffuse_prob = albedo_diffuse / total;
    b.phong_prob = albedo_phong / total;
    b.reflect_prob = albedo_reflect / total;
    b.refract_prob = albedo_refract / total;
    // The specular lobes' albedo: F mirror, plus 1 - F through a dielectric, written as
    // 1 - F (1 - mirror) so that a lossless dielectric continues with probability exactly 1.
    let one = vec3<f32>(1.0);
    let specular = select(b.fresnel * m.mirror, one - b.fresnel * (one - m.mirror), m.ior > 0.0);
    b.continuation = clamp(max_component(m.diffuse + m.phong + specular), 0.0, 1.0);
    b.is_delta = b.diffuse_prob == 0.0 && b.phong_prob == 0.0;
    return b;
}

fn reflect_local(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(-v.x, -v.y, v.z);
}

// The non-delta part of the BSDF for local direction `gen`, with the pdfs of sampling `gen`
// given `fix` (forward) and `fix` given `gen` (reverse).
struct BsdfEval {
    f: vec3<f32>,
    cos_gen: f32,
    pdf_forward: f32,
    pdf_reverse: f32,
}

fn bsdf_eval_local(b: Bsdf, gen: vec3<f32>) -> BsdfEval {
    var e = BsdfEval(vec3<f32>(0.0), abs(gen.z), 0.0, 0.0);
    if (gen.z * b.fix.z < 0.0 || b.fix.z < EPS_COSINE || gen.z < EPS_COSINE) {
        return e;
    }
    let m = b.m;
    if (b.diffuse_prob > 0.0) {
        e.f += m.diffuse * INV_PI;
        e.pdf_forward += b.diffuse_prob * gen.z * INV_PI;
        e.pdf_reverse += b.diffuse_prob * b.fix.z * INV_PI;
    }
    if (b.phong_prob > 0.0) {
        let cos_r = dot(reflect_local(b.fix), gen);
        if (cos_r > EPS_PHONG) {
            let pdf = b.phong_prob * power_cos_pdf(cos_r, m.phong_exponent);
            e.pdf_forward += pdf;
            e.pdf_reverse += pdf;
            e.f += m.phong * ((m.phong_exponent + 2.0) * 0.5 * INV_PI) * pow(cos_r, m.phong_exponent);
        }
    }
    return e;
}

// Evaluates for a world direction.
fn bsdf_eval(b: Bsdf, world_gen: vec3<f32>) -> BsdfEval {
    return bsdf_eval_local(b, to_local(b.frame, world_gen));
}

struct BsdfSample {
    direction: vec3<f32>,       // world
    f: vec3<f32>,               // BSDF value (delta lobes divided by the cosine)
    pdf: f32,                   // includes the lobe selection probability
    cos_gen: f32,
    specular: bool,
}

// Samples a direction with three uniform numbers; f = 0 means the sample is void.
fn bsdf_sample(b: Bsdf, u: vec3<f32>) -> BsdfSample {
    var s = BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    let m = b.m;
    var gen: vec3<f32>;
    if (u.z < b.diffuse_prob + b.phong_prob) {
        if (u.z < b.diffuse_prob) {
            if (b.fix.z < EPS_COSINE) {
                return s;
            }
            gen = sample_cos_hemisphere(u.xy);
        } else {
            let r = reflect_local(b.fix);
            gen = to_world(frame_from_z(r), sample_power_cos(u.xy, m.phong_exponent));
            if (dot(r, gen) <= EPS_PHONG) {
                return s;
            }
        }
        let e = bsdf_eval_local(b, gen);
        s.f = e.f;
        s.pdf = e.pdf_forward;
        if (s.pdf <= 0.0) {
            return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
        }
    } else if (u.z < b.diffuse_prob + b.phong_prob + b.reflect_prob) {
        gen = reflect_local(b.fix);
        s.pdf = b.reflect_prob;
        s.f = b.fresnel * m.mirror / abs(gen.z);
        s.specular = true;
    } else {
        if (m.ior < 0.0) {
            return s;
        }
        // Refraction is only picked where the Fresnel term let some light through, so cos_t > 0.
        var eta = 1.0 / m.ior;
        var cos_t = -b.cos_t;
        if (b.fix.z < 0.0) {
            eta = m.ior;
            cos_t = b.cos_t;
        }
        gen = vec3<f32>(-eta * b.fix.x, -eta * b.fix.y, cos_t);
        s.pdf = b.refract_prob;
        s.f = vec3<f32>((1.0 - b.fresnel) * select(eta * eta, 1.0, b.adjoint) / abs(cos_t));
        s.specular = true;
    }
    s.cos_gen = abs(gen.z);
    if (s.cos_gen < EPS_COSINE) {
        return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    }
    s.direction = to_world(b.frame, gen);
    return s;
}
