// The BSDFs. The Cornell-set BSDF (SmallVCM's model): a Lambertian lobe, a Phong lobe, and a
// mirror or smooth dielectric lobe, one lobe picked per sample in proportion to its albedo
// estimate; and, for materials with MATERIAL_PBR, glTF's metallic-roughness model (below
// `bsdf_sample`). Directions in the local frame have the geometric normal as +z. `fix` is the
// direction towards the previous path vertex; `gen` the one generated or evaluated. Radiance
// (camera) paths scale refraction by eta^2 = (ior on fix's side / ior on gen's side)^2;
// importance (light) paths, `adjoint`, do not. Works on a material resolved at the surface
// point (`material_at`). `bsdf_diffuse_part` and `bsdf_glossy_part` split a BSDF into its
// diffuse lobe and the rest (SPPM estimates photon density with the first and continues the
// camera path with the second).

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
    fresnel: f32,               // the Fresnel reflectance at `fix` (evaluations take it from here)
    cos_t: f32,                 // cosine of the refracted direction (0: none)
    is_delta: bool,
    valid: bool,
    pbr: bool,                  // glTF metallic-roughness (the fields below)
    alpha: f32,                 // GGX alpha; 0: the specular lobes are smooth (delta)
    spec_prob: f32,             // probability of the rough specular lobe (reflection and refraction)
    adjoint: bool,              // importance transport: refraction without the eta^2 scaling
#if SHADING_NORMALS
    ng: vec3<f32>,              // the geometric normal in the local (shading) frame
#endif
}

// The BSDF of material `m` at a stored vertex of normals `n` (VertexNormals, in
// shaders/lib/intersect.wgsl), reached from `towards_previous`.
fn vertex_bsdf(m: Material, n: VertexNormals, towards_previous: vec3<f32>) -> Bsdf {
    return bsdf_setup(m, vertex_geometric_normal(n), vertex_shading_normal(n), towards_previous);
}

// The lobes a part leaves out (`bsdf_diffuse_part`, `bsdf_glossy_part`), as bits of its
// material's flags above the scene's MATERIAL_* bits. The glTF model reads them; the SmallVCM
// lobes are left out by their probabilities alone.
const BSDF_NO_DIFFUSE: u32 = 0x40000000u;
const BSDF_NO_GLOSSY: u32 = 0x80000000u;

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

// The BSDF at surface `s` for a path arriving from `towards_previous`, with the material
// resolved there.
fn surface_bsdf(s: Surface, towards_previous: vec3<f32>) -> Bsdf {
    return bsdf_setup(material_at(s.material, s.tex), s.normal, s.shading_normal, towards_previous);
}

// The BSDF of `material` at a surface of geometric normal `ng` and shading normal `ns` (on
// the same side; equal without vertex normals), for a path arriving from `towards_previous`.
fn bsdf_setup(material: Material, ng: vec3<f32>, ns: vec3<f32>, towards_previous: vec3<f32>) -> Bsdf {
    var m = material;
    var b: Bsdf;
    // A two-sided material scatters on the side the path arrives from.
    let two_sided = (m.flags & MATERIAL_TWO_SIDED) != 0u;
    let flip = two_sided && dot(ng, towards_previous) < 0.0;
    b.frame = frame_from_z(select(ns, -ns, flip));
    b.fix = to_local(b.frame, towards_previous);
    b.m = m;
    b.valid = abs(b.fix.z) >= EPS_COSINE;
#if SHADING_NORMALS
    // Exactly +z where the normals are one (no rounding makes such a vertex look shaded).
    b.ng = select(to_local(b.frame, select(ng, -ng, flip)), vec3<f32>(0.0, 0.0, 1.0), all(ns == ng));
    b.valid = b.valid && b.fix.z * dot(b.ng, b.fix) > 0.0;
#endif
    b.adjoint = false;
    if (!b.valid) {
        return b;
    }
#if BSDF_PBR
    if ((m.flags & MATERIAL_PBR) != 0u) {
        if (!pbr_is_lambertian(m)) {
            return pbr_setup(b);
        }
        m = pbr_lambertian(m);
        b.m = m;
    }
#endif
    let albedo_diffuse = luminance(m.diffuse);
#if BSDF_PHONG
    let albedo_phong = luminance(m.phong);
#else
    let albedo_phong = 0.0;
#endif
#if BSDF_SPECULAR
    let fresnel = fresnel_dielectric(b.fix.z, m.ior);
    b.fresnel = fresnel.x;
    b.cos_t = fresnel.y;
    let albedo_reflect = b.fresnel * luminance(m.mirror);
    let albedo_refract = select(0.0, 1.0 - b.fresnel, m.ior > 0.0);
#else
    let albedo_reflect = 0.0;
    let albedo_refract = 0.0;
#endif
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
    b.continuation = smallvcm_continuation(b);
    b.is_delta = b.diffuse_prob == 0.0 && b.phong_prob == 0.0;
    return b;
}

// The SmallVCM lobes' Russian roulette continuation: their albedo bound at `fix` (through
// the Fresnel term in `b.fresnel`).
fn smallvcm_continuation(b: Bsdf) -> f32 {
    return clamp(max_component(b.m.diffuse + b.m.phong + bsdf_specular_albedo(b)), 0.0, 1.0);
}

// The continuation probability the BSDF at this vertex would have for a path arriving from
// world direction `towards` instead of its own `fix`: only the Fresnel terms depend on it, so
// no new set-up (photon mapping's MIS evaluates it for every photon). `b` must be valid.
fn bsdf_continuation_towards(b: Bsdf, towards: vec3<f32>) -> f32 {
    var l = b;
    l.fix = to_local(b.frame, towards);
#if BSDF_PBR
    if (b.pbr) {
        l.fresnel = pbr_fresnel(b.m, l.fix.z).x;
        return pbr_continuation(l);
    }
#endif
    l.fresnel = fresnel_dielectric(l.fix.z, b.m.ior).x;
    return smallvcm_continuation(l);
}

// The SmallVCM mirror or dielectric lobe's albedo at `fix`: F mirror, plus 1 - F through a
// dielectric, written as 1 - F (1 - mirror) so that a lossless dielectric continues with
// probability exactly 1.
fn bsdf_specular_albedo(b: Bsdf) -> vec3<f32> {
#if BSDF_SPECULAR
    let one = vec3<f32>(1.0);
    return select(b.fresnel * b.m.mirror, one - b.fresnel * (one - b.m.mirror), b.m.ior > 0.0);
#else
    return vec3<f32>(0.0);
#endif
}

// Whether the BSDF samples a diffuse lobe at its `fix`.
fn bsdf_has_diffuse(b: Bsdf) -> bool {
    return b.diffuse_prob > 0.0;
}

// Whether the BSDF samples a glossy or delta lobe at its `fix` (Phong, mirror, dielectric;
// glTF's specular reflection and transmission).
fn bsdf_has_glossy(b: Bsdf) -> bool {
    return b.phong_prob + b.spec_prob + b.reflect_prob + b.refract_prob > 0.0;
}

// `b` left without lobes to sample: invalid, never continued.
fn bsdf_no_lobes(b: Bsdf) -> Bsdf {
    var p = b;
    p.diffuse_prob = 0.0;
    p.phong_prob = 0.0;
    p.spec_prob = 0.0;
    p.reflect_prob = 0.0;
    p.refract_prob = 0.0;
    p.continuation = 0.0;
    p.is_delta = false;
    p.valid = false;
    return p;
}

// The BSDF restricted to its diffuse lobe: `bsdf_eval` gives the diffuse term alone, with the
// pdfs of sampling that lobe alone, and `bsdf_sample` samples it alone; continued with the
// lobe's albedo bound. Invalid without a diffuse lobe (`bsdf_has_diffuse`).
fn bsdf_diffuse_part(b: Bsdf) -> Bsdf {
    var d = bsdf_no_lobes(b);
    d.m.flags |= BSDF_NO_GLOSSY;
    if (!bsdf_has_diffuse(b)) {
        return d;
    }
    d.valid = b.valid;
    d.diffuse_prob = 1.0;
    var albedo = b.m.diffuse;
#if BSDF_PBR
    if (b.pbr) {
        let through = pbr_base_transmittance(b.m, b.fix.z, b.fresnel);
        albedo = (1.0 - b.m.metallic) * (1.0 - b.m.transmission) * through * pbr_base_albedo(b.m);
    }
#endif
    d.continuation = clamp(max_component(albedo), 0.0, 1.0);
    return d;
}

// The BSDF without its diffuse lobe: the glossy and delta lobes, picked in proportion to their
// probabilities in `b`; delta when only delta lobes are left; continued with their albedo
// bound. Invalid without such lobes (`bsdf_has_glossy`). With the diffuse part, `bsdf_eval`
// gives the whole BSDF's value: f(b) = f(diffuse part) + f(glossy part).
fn bsdf_glossy_part(b: Bsdf) -> Bsdf {
    var g = bsdf_no_lobes(b);
    g.m.flags |= BSDF_NO_DIFFUSE;
    let total = b.phong_prob + b.spec_prob + b.reflect_prob + b.refract_prob;
    if (total <= 0.0) {
        return g;
    }
    g.valid = b.valid;
    g.phong_prob = b.phong_prob / total;
    g.spec_prob = b.spec_prob / total;
    g.reflect_prob = b.reflect_prob / total;
    g.refract_prob = b.refract_prob / total;
    g.is_delta = g.phong_prob == 0.0 && g.spec_prob == 0.0;
    var albedo = b.m.phong + bsdf_specular_albedo(b);
#if BSDF_PBR
    if (b.pbr) {
        albedo = pbr_glossy_albedo(b);
    }
#endif
    g.continuation = clamp(max_component(albedo), 0.0, 1.0);
    return g;
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
#if BSDF_PBR
    if (b.pbr) {
        return pbr_eval_local(b, gen);
    }
#endif
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
#if BSDF_PHONG
    if (b.phong_prob > 0.0) {
        let cos_r = dot(reflect_local(b.fix), gen);
        if (cos_r > EPS_PHONG) {
            let pdf = b.phong_prob * power_cos_pdf(cos_r, m.phong_exponent);
            e.pdf_forward += pdf;
            e.pdf_reverse += pdf;
            e.f += m.phong * ((m.phong_exponent + 2.0) * 0.5 * INV_PI) * pow(cos_r, m.phong_exponent);
        }
    }
#endif
    return e;
}

// When the BSDF's non-delta part is a Lambertian alone (not glTF's model, no Phong lobe, no
// shading normal other than the geometric one): the
// value of `bsdf_eval(b, w).f` for every direction w with dot(w, b.frame.n) >= EPS_COSINE
// (it is 0 for the others). Otherwise -1. A sum of such values over many directions (a
// density estimation's) can then take the value out.
fn bsdf_lambertian_f(b: Bsdf) -> vec3<f32> {
#if SHADING_NORMALS
    if (bsdf_is_shaded(b)) {
        return vec3<f32>(-1.0);
    }
#endif
#if BSDF_PBR
    if (b.pbr) {
        return vec3<f32>(-1.0);
    }
#endif
#if BSDF_PHONG
    if (b.phong_prob > 0.0) {
        return vec3<f32>(-1.0);
    }
#endif
    if (b.diffuse_prob > 0.0 && b.fix.z >= EPS_COSINE) {
        return b.m.diffuse * INV_PI;
    }
    return vec3<f32>(0.0);
}

// Evaluates for a world direction.
fn bsdf_eval(b: Bsdf, world_gen: vec3<f32>) -> BsdfEval {
    let gen = to_local(b.frame, world_gen);
    var e = bsdf_eval_local(b, gen);
#if SHADING_NORMALS
    e.f *= bsdf_shading_factor(b, gen);
#endif
    return e;
}

// `bsdf_eval` for a density estimation (photon mapping's and VCM's merges) of light that
// arrived from `world_gen`: a photon's density is per unit area of the surface, so its
// incident cosine is the geometric one; with shading normals the value carries
// |gen.ns| / |gen.ng| as well, so that merges converge to what the estimators that sample
// light by direction converge to (they weigh it with the shading cosine).
fn bsdf_eval_merge(b: Bsdf, world_gen: vec3<f32>) -> BsdfEval {
    var e = bsdf_eval(b, world_gen);
#if SHADING_NORMALS
    let gen = to_local(b.frame, world_gen);
    let g = dot(b.ng, gen);
    // g = 0 is a direction the normals disagree about: e.f is 0 already.
    if (g != 0.0) {
        e.f *= abs(gen.z / g);
    }
#endif
    return e;
}

#if SHADING_NORMALS
// The factor shading normals put on the BSDF's value for local direction `gen` (see the top
// of this file): 0 where the geometric and the shading normal disagree on gen's side; for
// importance transport, the adjoint correction |fix.ns| |gen.ng| / (|fix.ng| |gen.ns|).
fn bsdf_shading_factor(b: Bsdf, gen: vec3<f32>) -> f32 {
    let g_gen = dot(b.ng, gen);
    if (g_gen * gen.z <= 0.0) {
        return 0.0;
    }
    if (b.adjoint) {
        return abs((b.fix.z * g_gen) / (dot(b.ng, b.fix) * gen.z));
    }
    return 1.0;
}

// Whether the shading normal differs from the geometric one at this vertex.
fn bsdf_is_shaded(b: Bsdf) -> bool {
    return b.ng.z < 1.0;
}
#endif

struct BsdfSample {
    direction: vec3<f32>,       // world
    f: vec3<f32>,               // BSDF value (delta lobes divided by the cosine)
    pdf: f32,                   // includes the lobe selection probability
    cos_gen: f32,
    specular: bool,
}

// Samples a direction with three uniform numbers; f = 0 means the sample is void.
fn bsdf_sample(b: Bsdf, u: vec3<f32>) -> BsdfSample {
    var s = bsdf_sample_lobes(b, u);
#if SHADING_NORMALS
    s.f *= bsdf_shading_factor(b, to_local(b.frame, s.direction));
#endif
    return s;
}

// `bsdf_sample` without the shading normals' factor.
fn bsdf_sample_lobes(b: Bsdf, u: vec3<f32>) -> BsdfSample {
#if BSDF_PBR
    if (b.pbr) {
        return pbr_sample(b, u);
    }
#endif
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
#if BSDF_PHONG
            let r = reflect_local(b.fix);
            gen = to_world(frame_from_z(r), sample_power_cos(u.xy, m.phong_exponent));
            if (dot(r, gen) <= EPS_PHONG) {
                return s;
            }
#else
            return s;
#endif
        }
        let e = bsdf_eval_local(b, gen);
        s.f = e.f;
        s.pdf = e.pdf_forward;
        if (s.pdf <= 0.0) {
            return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
        }
#if BSDF_SPECULAR
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
#else
    } else {
        return s;
    }
#endif
    s.cos_gen = abs(gen.z);
    if (s.cos_gen < EPS_COSINE) {
        return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    }
    s.direction = to_world(b.frame, gen);
    return s;
}

#if BSDF_PBR
// glTF 2.0 metallic-roughness, with KHR_materials_transmission and KHR_materials_ior.
// Three lobes on a macro-surface of dielectric index `ior` (clamped to at least PBR_MIN_IOR;
// a material with no metal, no transmission and an index of at most PBR_MIN_IOR has no
// specular layer and is set up as a Lambertian, `pbr_is_lambertian`):
// - specular reflection, GGX microfacets with height-correlated Smith masking-shadowing:
//   D G2 / (4 |cos_o| |cos_i|) x (metallic Schlick(base colour, o.h) + (1 - metallic) F(o.h)),
//   F the exact dielectric Fresnel reflectance; the metal part only on the outside (+z);
// - specular transmission through the same microfacets (Walter et al. 2007), tinted by
//   (1 - metallic) transmission base colour, with (1 - F(o.h)), on both sides; through a
//   thin-walled sheet (MATERIAL_THIN_WALLED, compiled in with BSDF_THIN_WALLED) the light
//   is not bent: smooth, it leaves along -fix; rough, along the GGX reflection at the
//   sampled microfacet mirrored through the surface plane, so that its value, pdfs and
//   sampling are reflection's with (1 - F) tint for the colour, and, with no change of
//   medium, nothing scales it by eta^2. A sheet's F is that of a slab of two faces
//   (`pbr_fresnel`), in every lobe;
// - diffuse on the outside only: (1 - metallic) (1 - transmission) base / pi, scaled by
//   (1 - F(cos_o)) (1 - F(cos_i)), the light that enters and leaves through a smooth
//   interface: symmetric, so reciprocal, and with reflection never above 1 (the light the
//   interface reflects back down is dropped: a white base reflects 1 - F_avg of the
//   diffuse light, 0.91 for ior 1.5); Mitsuba's plastic returns it to the base
//   (`pbr_diffuse_reflectance`), and its rough plastic's coating lets through its tabulated
//   transmittance T(cos) instead of 1 - F(cos) (`pbr_base_transmittance`).
// Opaque materials (no transmission) are black from behind. Roughness (perceptual, in [0, 1])
// gives alpha = roughness^2; below PBR_SMOOTH_ALPHA (roughness 0.0316) the specular lobes are
// smooth: a perfect mirror for metals, a smooth dielectric for glass (delta lobes), so alpha
// never underflows and no pdf is infinite. A sample first picks diffuse or specular in
// proportion to the lobes' albedo estimates at `fix`; specular samples a visible microfacet
// normal, then reflects or refracts in proportion to the reflected and transmitted weights at
// that normal. The reverse pdf makes the same choices at `gen`. The parts split the BSDF
// between the diffuse lobe and the specular lobes (reflection and transmission, smooth or
// rough), each sampled as if it were the only one.

const PBR_SMOOTH_ALPHA: f32 = 1e-3;
const PBR_MIN_IOR: f32 = 1.001;

// Whether a PBR material is a Lambertian: no metal, no transmission, and no specular layer
// (an index of refraction of at most PBR_MIN_IOR, which KHR_materials_specular 0 and the
// Mitsuba import of a textured diffuse give; a rough plastic's coating masks light whatever
// its index). It is then set up as the Lambertian lobe of its base colour (photon mapping's
// gathers evaluate the BSDF for every photon they find).
fn pbr_is_lambertian(m: Material) -> bool {
    return m.metallic == 0.0 && m.transmission == 0.0 && m.ior <= PBR_MIN_IOR && !pbr_rough_plastic(m);
}

// The Lambertian lobe of a PBR material's base colour (pbr_is_lambertian).
fn pbr_lambertian(m: Material) -> Material {
    var l = m;
    l.flags &= ~MATERIAL_PBR;
    l.phong = vec3<f32>(0.0);
    l.mirror = vec3<f32>(0.0);
    l.ior = -1.0;
    return l;
}

// Whether the material is a thin-walled sheet (its light passes through unbent).
fn pbr_thin(m: Material) -> bool {
#if BSDF_THIN_WALLED
    return (m.flags & MATERIAL_THIN_WALLED) != 0u;
#else
    return false;
#endif
}

// The dielectric's reflectance for a direction of local z `cos_w` (or a microfacet seen at
// that cosine, signed by the side), and the cosine of the transmitted direction (0: none):
// those of a solid interface (`fresnel_dielectric`), or of a thin sheet, the same on both
// sides: a slab of two faces of reflectance R each, among which light reflects back and
// forth unabsorbed, reflects R + (1 - R)^2 R / (1 - R^2) = 2R / (1 + R), and lets the rest
// through at the angle it came in.
fn pbr_fresnel(m: Material, cos_w: f32) -> vec2<f32> {
    if (pbr_thin(m)) {
        let r = fresnel_dielectric(abs(cos_w), m.ior).x;
        return vec2<f32>(2.0 * r / (1.0 + r), abs(cos_w));
    }
    return fresnel_dielectric(cos_w, m.ior);
}

// The metal's Fresnel reflectance at cosine `c` (> 0) to the normal: glTF's, Schlick's from
// the base colour; or, for a conductor of complex index eta + i k (MATERIAL_CONDUCTOR: eta in
// `mirror`, k in `phong`; Mitsuba's conductors), the exact unpolarised reflectance tinted by
// the base colour (Mitsuba's specular_reflectance). (eta, k) = (0, 0) reflects everything
// (Mitsuba's `none`).
fn pbr_metal_fresnel(m: Material, c: f32) -> vec3<f32> {
    if ((m.flags & MATERIAL_CONDUCTOR) != 0u) {
        return m.diffuse * fresnel_conductor(c, m.mirror, m.phong);
    }
    return fresnel_schlick(m.diffuse, c);
}

// The unpolarised Fresnel reflectance of a conductor of complex index eta + i k (relative to
// the outside) at cosine `c` of the incident direction.
fn fresnel_conductor(c: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let eta2 = eta * eta;
    let k2 = k * k;
    let t0 = eta2 - k2 - vec3<f32>(s2);
    let a2b2 = sqrt(t0 * t0 + 4.0 * eta2 * k2);
    let t1 = a2b2 + vec3<f32>(c2);
    let a = sqrt(max(0.5 * (a2b2 + t0), vec3<f32>(0.0)));
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / max(t1 + t2, vec3<f32>(1e-30));
    let t3 = c2 * a2b2 + vec3<f32>(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / max(t3 + t4, vec3<f32>(1e-30));
    return 0.5 * (rp + rs);
}

// Whether the material's microfacets follow Beckmann's distribution (else GGX's).
fn pbr_beckmann(m: Material) -> bool {
#if BSDF_BECKMANN
    return (m.flags & MATERIAL_BECKMANN) != 0u;
#else
    return false;
#endif
}

// The microfacet distribution's density of normals `h` at the BSDF's alpha.
fn pbr_d(b: Bsdf, h: vec3<f32>) -> f32 {
#if BSDF_BECKMANN
    if (pbr_beckmann(b.m)) {
        return beckmann_d(h, b.alpha);
    }
#endif
    return ggx_d(h, b.alpha);
}

// The distribution's Smith Lambda for direction `w`.
fn pbr_lambda(b: Bsdf, w: vec3<f32>) -> f32 {
#if BSDF_BECKMANN
    if (pbr_beckmann(b.m)) {
        return beckmann_lambda(w, b.alpha);
    }
#endif
    return ggx_lambda(w, b.alpha);
}

// Masking of direction `w`.
fn pbr_g1(b: Bsdf, w: vec3<f32>) -> f32 {
    return 1.0 / (1.0 + pbr_lambda(b, w));
}

// Masking of direction `w` as Mitsuba's separable masking-shadowing takes it: Smith's, but for
// Beckmann Walter et al.'s fit of it, as Mitsuba evaluates its BSDFs (the visible normals
// are still sampled, and their pdf evaluated, with Smith's).
fn pbr_separable_g1(b: Bsdf, w: vec3<f32>) -> f32 {
#if BSDF_BECKMANN
    if (pbr_beckmann(b.m)) {
        return beckmann_g1_fit(w, b.alpha);
    }
#endif
    return pbr_g1(b, w);
}

// Masking-shadowing of the pair `o`, `i` (either side of the surface): height-correlated
// (glTF's), or the product of the two maskings (MATERIAL_SMITH_SEPARABLE: Mitsuba's).
fn pbr_g2(b: Bsdf, o: vec3<f32>, i: vec3<f32>) -> f32 {
    if ((b.m.flags & MATERIAL_SMITH_SEPARABLE) != 0u) {
        return pbr_separable_g1(b, o) * pbr_separable_g1(b, i);
    }
    return 1.0 / (1.0 + pbr_lambda(b, o) + pbr_lambda(b, i));
}

// Density of sampling the microfacet normal `h` with `pbr_sample_visible` from `w` (w.z > 0):
// G1(w) max(0, w.h) D(h) / w.z.
fn pbr_visible_pdf(b: Bsdf, w: vec3<f32>, h: vec3<f32>) -> f32 {
    let wh = dot(w, h);
    if (wh <= 0.0 || w.z <= 0.0) {
        return 0.0;
    }
    return pbr_g1(b, w) * wh * pbr_d(b, h) / w.z;
}

// A microfacet normal visible from `w` (w.z > 0), with density `pbr_visible_pdf`.
fn pbr_sample_visible(b: Bsdf, w: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
#if BSDF_BECKMANN
    if (pbr_beckmann(b.m)) {
        return beckmann_sample_visible(w, b.alpha, u);
    }
#endif
    return ggx_sample_visible(w, b.alpha, u);
}

// The diffuse base's reflectance as its lobe weighs it: the base colour; for Mitsuba's plastic
// (MATERIAL_PLASTIC), the base with the light the coating reflects back into it, scattered
// again: base / (1 - F_dr) (nonlinear: base / (1 - base F_dr)), F_dr the coating's internal
// diffuse reflectance, and over ior^2 (radiance leaving into the outer medium spreads over
// the wider solid angle). With the (1 - F(cos_o)) (1 - F(cos_i)) of the smooth plastic's lobe,
// a white linear plastic reflects 1 in all (F_dr's identity 1 - F_dr(outside) =
// ior^2 (1 - F_dr(inside))).
fn pbr_diffuse_reflectance(m: Material) -> vec3<f32> {
    if ((m.flags & MATERIAL_PLASTIC) == 0u) {
        return m.diffuse;
    }
    let coating = plastic_coating(m);
    let kept = select(vec3<f32>(coating.x), m.diffuse * coating.x, (m.flags & MATERIAL_PLASTIC_NONLINEAR) != 0u);
    return m.diffuse * coating.y / (vec3<f32>(1.0) - kept);
}

// A plastic's coating: F_dr, its reflectance of the base's diffuse light back into it
// (Mitsuba's fit for a smooth coating, the table of a rough one), and 1 / ior^2.
fn plastic_coating(m: Material) -> vec2<f32> {
#if BSDF_ROUGH_PLASTIC
    if (pbr_rough_plastic(m)) {
        let table = rough_plastic_table(m);
        return vec2<f32>(plastic_tables[table], plastic_tables[table + 1u]);
    }
#endif
    return vec2<f32>(fresnel_diffuse_reflectance(1.0 / m.ior), 1.0 / (m.ior * m.ior));
}

// The share of the light arriving at local z `cos_w` (> 0) that the interface lets through to
// the diffuse base, given its Fresnel reflectance `f` there: 1 - f; Mitsuba's rough plastic's
// coating transmits its table's T(cos_w).
fn pbr_base_transmittance(m: Material, cos_w: f32, f: f32) -> f32 {
#if BSDF_ROUGH_PLASTIC
    if (pbr_rough_plastic(m)) {
        return rough_plastic_transmittance(m, cos_w);
    }
#endif
    return 1.0 - f;
}

// What the diffuse base sends back out per unit of the light let through to it, at most: its
// colour (a smooth interface lets out less than the base reflects, a smooth plastic's base
// reflects as much in all); a rough plastic's, its lobe's reflectance times its coating's
// hemispherical transmittance, exactly.
fn pbr_base_albedo(m: Material) -> vec3<f32> {
#if BSDF_ROUGH_PLASTIC
    if (pbr_rough_plastic(m)) {
        return pbr_diffuse_reflectance(m) * plastic_tables[rough_plastic_table(m) + 2u];
    }
#endif
    return m.diffuse;
}

// Whether the material is Mitsuba's rough plastic, with its coating's table.
fn pbr_rough_plastic(m: Material) -> bool {
#if BSDF_ROUGH_PLASTIC
    return (m.flags & MATERIAL_ROUGH_PLASTIC) != 0u;
#else
    return false;
#endif
}

#if BSDF_ROUGH_PLASTIC
// Where a rough plastic's coating table starts in `plastic_tables` (scenes/src/plastic.rs):
// F_dr, 1 / ior^2, the hemispherical transmittance, then T at the cosines k / 63,
// k = 0 ..= 63.
fn rough_plastic_table(m: Material) -> u32 {
    return u32(m.phong_exponent);
}

// The rough coating's transmittance T at cosine `cos_w`, interpolated linearly in cos_w * 63
// between the table's entries, as Mitsuba interpolates it.
fn rough_plastic_transmittance(m: Material, cos_w: f32) -> f32 {
    let x = clamp(cos_w, 0.0, 1.0) * 63.0;
    let k = min(u32(x), 62u);
    let entry = rough_plastic_table(m) + 3u + k;
    return mix(plastic_tables[entry], plastic_tables[entry + 1u], x - f32(k));
}
#endif

// The hemispherical average of the Fresnel reflectance, weighted by the cosine, of light
// arriving in a medium of relative index `eta` (the index beyond over the index it is in):
// the fits Mitsuba uses (Egan and Hilgeman 1973 below 1, d'Eon and Irving 2011 above).
fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if (eta < 1.0) {
        return 0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681;
    }
    return 0.919317 + inv * (-3.4793 + inv * (6.75335 + inv * (-7.80989 + inv * (4.98554 - inv * 1.36881))));
}

fn pbr_setup(bsdf: Bsdf) -> Bsdf {
    var b = bsdf;
    let m = b.m;
    b.pbr = true;
    // A rough plastic keeps its index, however close to 1 (the host checked it is positive and
    // not 1): nothing refracts through its coating, whose table stands for it.
    b.m.ior = select(max(m.ior, PBR_MIN_IOR), m.ior, pbr_rough_plastic(m));
    let roughness = clamp(m.roughness, 0.0, 1.0);
    b.alpha = select(roughness * roughness, 0.0, roughness * roughness < PBR_SMOOTH_ALPHA);
    let fresnel = pbr_fresnel(b.m, b.fix.z);
    b.fresnel = fresnel.x;
    b.cos_t = fresnel.y;
    let lobes = pbr_lobe_probs(b, b.fix.z);
    b.diffuse_prob = lobes.y;
    b.spec_prob = lobes.x;
    if (b.alpha == 0.0) {
        let w = pbr_spec_weights(b, b.fix.z > 0.0, abs(b.fix.z), b.fresnel);
        b.reflect_prob = b.spec_prob * w.x / max(w.x + w.y, 1e-30);
        b.refract_prob = b.spec_prob - b.reflect_prob;
        b.spec_prob = 0.0;
    }
    b.continuation = pbr_continuation(b);
    if (b.diffuse_prob + b.spec_prob + b.reflect_prob + b.refract_prob <= 0.0) {
        b.continuation = 0.0;
    }
    b.is_delta = b.diffuse_prob == 0.0 && b.spec_prob == 0.0;
    return b;
}

// The albedo bound of the specular lobes alone: the interface's reflection, the light it lets
// through the surface, and the metal on the outside (`pbr_setup`'s bound less the diffuse
// base's (1 - metallic) (1 - transmission) (1 - F) base).
fn pbr_glossy_albedo(b: Bsdf) -> vec3<f32> {
    let m = b.m;
    let through = pbr_base_transmittance(m, b.fix.z, b.fresnel);
    let dielectric = (1.0 - m.metallic) * ((1.0 - through) + through * m.transmission * m.diffuse);
    var bound = select(vec3<f32>(0.0), dielectric, pbr_scatters(b, b.fix.z));
    if (b.fix.z > 0.0) {
        bound += m.metallic * pbr_metal_fresnel(m, b.fix.z);
    }
    return bound;
}

// The Russian roulette continuation: the albedo bound at `fix`, everything the interface does
// not let through (`b.fresnel`; a rough coating reflects at most 1 - T) plus what the base
// sends back of what it does, metal on the outside.
fn pbr_continuation(b: Bsdf) -> f32 {
    let m = b.m;
    let through = pbr_base_transmittance(m, b.fix.z, b.fresnel);
    let dielectric = (1.0 - m.metallic) * ((1.0 - through) + through * pbr_base_albedo(m));
    var bound = select(vec3<f32>(0.0), dielectric, pbr_scatters(b, b.fix.z));
    if (b.fix.z > 0.0) {
        bound += m.metallic * pbr_metal_fresnel(m, b.fix.z);
    }
    return clamp(max_component(bound), 0.0, 1.0);
}

fn pbr_transmissive(b: Bsdf) -> bool {
    return b.m.transmission > 0.0 && b.m.metallic < 1.0;
}

// Whether anything scatters for a direction with local z `cos_w`: opaque materials are black
// from behind.
fn pbr_scatters(b: Bsdf, cos_w: f32) -> bool {
    return cos_w > 0.0 || pbr_transmissive(b);
}

// Probabilities of the specular and diffuse lobes for a path arriving from a direction with
// local z `cos_w`, in proportion to their albedo estimates (luminance of the weights at the
// macro-surface normal).
fn pbr_lobe_probs(b: Bsdf, cos_w: f32) -> vec2<f32> {
    if (!pbr_scatters(b, cos_w)) {
        return vec2<f32>(0.0);
    }
    let m = b.m;
    let f = pbr_fresnel(m, cos_w).x;
    let w = pbr_spec_weights(b, cos_w > 0.0, abs(cos_w), f);
    var diffuse = 0.0;
    if (cos_w > 0.0) {
        let through = pbr_base_transmittance(m, cos_w, f);
        diffuse = (1.0 - m.metallic) * (1.0 - m.transmission) * luminance(m.diffuse) * through;
    }
    let total = w.x + w.y + diffuse;
    if (total <= 1e-9) {
        return vec2<f32>(0.0);
    }
    // A part samples the lobes it keeps as if they were the only ones.
    let kept = vec2<f32>(
        select(w.x + w.y, 0.0, (m.flags & BSDF_NO_GLOSSY) != 0u),
        select(diffuse, 0.0, (m.flags & BSDF_NO_DIFFUSE) != 0u),
    );
    return kept / max(kept.x + kept.y, 1e-30);
}

// Luminance weights of specular reflection (x) and refraction (y) at a microfacet seen at
// cosine `cos_h` (> 0) from the outside (`outside`) or the inside, with dielectric Fresnel
// reflectance `f` there.
fn pbr_spec_weights(b: Bsdf, outside: bool, cos_h: f32, f: f32) -> vec2<f32> {
    let m = b.m;
    var reflected = (1.0 - m.metallic) * f;
    if (outside) {
        reflected += m.metallic * luminance(pbr_metal_fresnel(m, cos_h));
    }
    let refracted = (1.0 - m.metallic) * m.transmission * luminance(m.diffuse) * (1.0 - f);
    return vec2<f32>(reflected, refracted);
}

// The specular reflectance at a microfacet seen at cosine `cos_h` with dielectric Fresnel `f`.
fn pbr_spec_color(b: Bsdf, outside: bool, cos_h: f32, f: f32) -> vec3<f32> {
    var c = vec3<f32>((1.0 - b.m.metallic) * f);
    if (outside) {
        c += b.m.metallic * pbr_metal_fresnel(b.m, cos_h);
    }
    return c;
}

// Probability of reflecting (rather than refracting) at a sampled microfacet.
fn pbr_reflect_prob(w: vec2<f32>) -> f32 {
    return select(w.x / (w.x + w.y), 1.0, w.x + w.y <= 0.0);
}

fn pbr_eval_local(b: Bsdf, gen: vec3<f32>) -> BsdfEval {
    var e = BsdfEval(vec3<f32>(0.0), abs(gen.z), 0.0, 0.0);
    let o = b.fix;
    let outside_o = o.z > 0.0;
    let outside_i = gen.z > 0.0;
    if (abs(gen.z) < EPS_COSINE || !pbr_scatters(b, o.z) || !pbr_scatters(b, gen.z)) {
        return e;
    }
    let m = b.m;
    // The lobe probabilities at `fix` are the set-up's (those of the rough specular lobe and
    // the diffuse one; a part's renormalised).
    let lobes_o = vec2<f32>(b.spec_prob, b.diffuse_prob);
    let lobes_i = pbr_lobe_probs(b, gen.z);
    // The set-up's `pbr_fresnel(m, o.z).x`: evaluated once a vertex, not once an evaluation.
    let f_o = b.fresnel;
    let f_i = pbr_fresnel(m, gen.z).x;
    if (outside_o && outside_i && (m.flags & BSDF_NO_DIFFUSE) == 0u) {
        let through = pbr_base_transmittance(m, o.z, f_o) * pbr_base_transmittance(m, gen.z, f_i);
        let diffuse = (1.0 - m.metallic) * (1.0 - m.transmission) * through * INV_PI;
        e.f += pbr_diffuse_reflectance(m) * diffuse;
        e.pdf_forward += lobes_o.y * gen.z * INV_PI;
        e.pdf_reverse += lobes_i.y * o.z * INV_PI;
    }
    if (b.alpha == 0.0 || (m.flags & BSDF_NO_GLOSSY) != 0u) {
        return e;
    }
    if (outside_o == outside_i || pbr_thin(m)) {
        return pbr_eval_mirrored(b, gen, e, lobes_i.x);
    }
    // The frame mirrored so that `fix` is above the surface; `eta` = ior below / ior above.
    let s = select(-1.0, 1.0, outside_o);
    let wo = vec3<f32>(o.xy, s * o.z);
    let wi = vec3<f32>(gen.xy, s * gen.z);
    let alpha = b.alpha;
    // Refraction: the generalised half vector, on the side of `fix`.
    let eta = select(1.0 / m.ior, m.ior, outside_o);
    let hv = wo + eta * wi;
    if (dot(hv, hv) < 1e-12) {
        return e;
    }
    var h = normalize(hv);
    h = select(h, -h, h.z < 0.0);
    let c_o = dot(wo, h);
    let c_i = dot(wi, h);
    if (c_o <= 0.0 || c_i >= 0.0) {
        return e;
    }
    let f = fresnel_dielectric(s * c_o, m.ior).x;
    let denom = c_o + eta * c_i;
    let d = pbr_d(b, h);
    let value = (1.0 - f) * d * pbr_g2(b, wo, wi) * c_o * (-c_i) / (wo.z * (-wi.z) * denom * denom);
    let tint = (1.0 - m.metallic) * m.transmission * m.diffuse;
    e.f = tint * value * select(1.0, eta * eta, b.adjoint);
    // The reverse choice is made at `gen` (inside if `fix` is outside): the same Fresnel
    // factor (reflectance is equal at both angles of a refraction), other weights.
    let p_forward = 1.0 - pbr_reflect_prob(pbr_spec_weights(b, outside_o, c_o, f));
    let p_reverse = 1.0 - pbr_reflect_prob(pbr_spec_weights(b, outside_i, -c_i, f));
    let vis_o = pbr_g1(b, wo) * c_o * d / wo.z;
    let vis_i = pbr_g1(b, wi) * (-c_i) * d / (-wi.z);
    e.pdf_forward = lobes_o.x * p_forward * vis_o * eta * eta * (-c_i) / (denom * denom);
    e.pdf_reverse = lobes_i.x * p_reverse * vis_i * c_o / (denom * denom);
    return e;
}

// `e` (the diffuse lobe's part at `e`'s direction, `gen`) plus the rough specular lobe's
// reflection, or, through a thin sheet, transmission, which is reflection mirrored through the
// surface plane: both directions are taken to the side of `fix`, where they meet at the
// microfacet normal h of a reflection. `spec_i` is the rough specular lobe's probability
// for a path arriving from `gen`.
fn pbr_eval_mirrored(b: Bsdf, gen: vec3<f32>, e: BsdfEval, spec_i: f32) -> BsdfEval {
    var r = e;
    let outside_o = b.fix.z > 0.0;
    let outside_i = gen.z > 0.0;
    let transmits = outside_o != outside_i;
    let s = select(-1.0, 1.0, outside_o);
    let wo = vec3<f32>(b.fix.xy, s * b.fix.z);
    let wi = vec3<f32>(gen.xy, abs(gen.z));
    let h = normalize(wo + wi);
    let c = dot(wo, h);
    if (c <= 0.0) {
        return r;
    }
    let f = pbr_fresnel(b.m, s * c).x;
    let lobe = pbr_d(b, h) * pbr_g2(b, wo, wi) / (4.0 * wo.z * wi.z);
    let tint = (1.0 - b.m.metallic) * b.m.transmission * b.m.diffuse;
    r.f += select(pbr_spec_color(b, outside_o, c, f), (1.0 - f) * tint, transmits) * lobe;
    // Each direction picks reflection or transmission with the weights of its own side.
    let p_o = pbr_reflect_prob(pbr_spec_weights(b, outside_o, c, f));
    let p_i = pbr_reflect_prob(pbr_spec_weights(b, outside_i, c, f));
    r.pdf_forward += b.spec_prob * select(p_o, 1.0 - p_o, transmits) * pbr_visible_pdf(b, wo, h) / (4.0 * c);
    r.pdf_reverse += spec_i * select(p_i, 1.0 - p_i, transmits) * pbr_visible_pdf(b, wi, h) / (4.0 * c);
    return r;
}

fn pbr_sample(b: Bsdf, u: vec3<f32>) -> BsdfSample {
    var s = BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    let o = b.fix;
    let m = b.m;
    var gen: vec3<f32>;
    if (u.z < b.diffuse_prob) {
        gen = sample_cos_hemisphere(u.xy);
    } else if (b.alpha == 0.0) {
        // Smooth specular: the interface's own reflection or refraction.
        if (u.z < b.diffuse_prob + b.reflect_prob) {
            gen = reflect_local(o);
            s.pdf = b.reflect_prob;
            s.f = pbr_spec_color(b, o.z > 0.0, abs(o.z), b.fresnel) / abs(o.z);
        } else {
            if (b.refract_prob <= 0.0 || b.cos_t <= 0.0) {
                return s;
            }
            var eta = 1.0 / m.ior;              // ior of fix's side over gen's
            var cos_t = -b.cos_t;
            if (o.z < 0.0) {
                eta = m.ior;
                cos_t = b.cos_t;
            }
            // A thin sheet's cos_t is |o.z|: the light leaves along -o, in the same medium.
            eta = select(eta, 1.0, pbr_thin(m));
            gen = vec3<f32>(-eta * o.x, -eta * o.y, cos_t);
            s.pdf = b.refract_prob;
            let tint = (1.0 - m.metallic) * m.transmission * m.diffuse;
            s.f = tint * ((1.0 - b.fresnel) * select(eta * eta, 1.0, b.adjoint) / abs(cos_t));
        }
        s.specular = true;
        s.cos_gen = abs(gen.z);
        if (s.cos_gen < EPS_COSINE) {
            return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
        }
        s.direction = to_world(b.frame, gen);
        return s;
    } else {
        let outside = o.z > 0.0;
        let side = select(-1.0, 1.0, outside);
        let wo = vec3<f32>(o.xy, side * o.z);
        let h = pbr_sample_visible(b, wo, u.xy);
        let c = dot(wo, h);
        if (c <= 0.0) {
            return s;
        }
        let f = pbr_fresnel(m, side * c).x;
        let p_reflect = pbr_reflect_prob(pbr_spec_weights(b, outside, c, f));
        // The lobe's share of u.z, rescaled to [0, 1), picks reflection or refraction.
        let v = (u.z - b.diffuse_prob) / max(b.spec_prob, 1e-30);
        var wi: vec3<f32>;
        if (v < p_reflect || pbr_thin(m)) {
            wi = 2.0 * c * h - wo;
            if (wi.z <= 0.0) {
                return s;
            }
            // Through a thin sheet, transmission is that reflection mirrored to the other side.
            wi.z = select(wi.z, -wi.z, v >= p_reflect);
        } else {
            let eta = select(1.0 / m.ior, m.ior, outside);      // ior below / ior above
            let sin2_t = (1.0 - c * c) / (eta * eta);
            if (sin2_t >= 1.0) {
                return s;
            }
            let cos_t = sqrt(1.0 - sin2_t);
            wi = (c / eta - cos_t) * h - wo / eta;
            if (wi.z >= 0.0) {
                return s;
            }
        }
        gen = vec3<f32>(wi.xy, side * wi.z);
    }
    let e = pbr_eval_local(b, gen);
    if (e.pdf_forward <= 0.0) {
        return s;
    }
    s.f = e.f;
    s.pdf = e.pdf_forward;
    s.cos_gen = e.cos_gen;
    s.direction = to_world(b.frame, gen);
    return s;
}
#endif
