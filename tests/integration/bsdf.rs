//! The BSDFs on the GPU (`shaders/lib/bsdf.wgsl`), through the probe harness: sampled
//! directions against the pdfs (chi-square), the pdfs' integrals and lost samples, albedo
//! (white furnace), reciprocity, forward/reverse pdf consistency; the same of the BSDF's
//! diffuse and glossy parts (`bsdf_diffuse_part`, `bsdf_glossy_part`), which must add up to
//! the whole BSDF; and a PBR scene that must render its exact radiance. Thin-walled glTF
//! transmission gets the same checks, and a render: a thin pane in front of a light neither
//! moves its image nor dims it by more than the slab's reflectance.
//!
//! The BSDF sits on a surface with normal +z (the local frame is the world frame); `fix` is
//! the direction towards the previous vertex.

use crate::chi2::{SphereBins, goodness_of_fit, significance};
use crate::common::{region, render};
use crate::probe::{probe, scene};
use lightgraph::run::LoadedScene;
use lightgraph_engine::ConstValue;

/// The chi-square tests in this file, for the Šidák-corrected significance of each.
const CHI2_TESTS: u32 = 38;
/// Samples per chi-square test: with 24 × 48 bins, a smooth lobe expects about 200 per bin.
/// Bins where a pdf's support ends (rough refraction's) need the fine sub-grid: at 4 × 4
/// points the midpoint rule misses enough of their mass to fail the test.
const SAMPLES: u32 = 200_000;
/// Quadrature sub-grid per bin (the integral's error is estimated from half of it), on the
/// sphere and in the caps around narrow lobes.
const SUB: usize = 8;
const SUB_CAP: usize = 8;

/// The BSDF a probe sets up (the constant `PART`): the whole one or one of its parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Part {
    Whole,
    Diffuse,
    Glossy,
}

const SETUP: &str = "
fn probe_bsdf(towards_previous: vec3<f32>, adjoint: bool) -> Bsdf {
    let n = vec3<f32>(0.0, 0.0, 1.0);
    var b = bsdf_setup(material_at(0u, vec2<f32>(0.0)), n, n, normalize(towards_previous));
    b.adjoint = adjoint;
    if (PART == 1u) {
        return bsdf_diffuse_part(b);
    }
    if (PART == 2u) {
        return bsdf_glossy_part(b);
    }
    return b;
}
";

/// Per index: the sampled direction with its kind in w (0 none, 1 continuous, 2 delta
/// reflection, 3 delta refraction, -1 continuous where the pdf is 0), and the weight
/// f cos / pdf. Each part draws numbers of its own.
const SAMPLE: &str = "
fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let b = probe_bsdf(vec3<f32>(FIX_X, FIX_Y, FIX_Z), ADJOINT);
    var rng = rng_seed(frame.seed, frame.index, index + PART * N);
    let u = vec3<f32>(rng_f32(&rng), rng_f32(&rng), rng_f32(&rng));
    let s = bsdf_sample(b, u);
    var kind = 0.0;
    var weight = vec3<f32>(0.0);
    if (b.valid && s.pdf > 0.0) {
        kind = select(1.0, select(3.0, 2.0, s.direction.z * FIX_Z > 0.0), s.specular);
        weight = s.f * s.cos_gen / s.pdf;
        // A continuous sample must have a positive pdf at its own direction.
        if (!s.specular && bsdf_eval(b, s.direction).pdf_forward <= 0.0) {
            kind = -1.0;
        }
    }
    out[index * PER_INDEX] = vec4<f32>(s.direction, kind);
    out[index * PER_INDEX + 1u] = vec4<f32>(weight, 0.0);
    return false;
}
";

/// Per input direction: (f, pdf_forward), (pdf_reverse, cos). The last index writes the
/// setup: (diffuse, rough specular, delta reflection, delta refraction probabilities),
/// (continuation, is_delta, valid).
const EVAL: &str = "
fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let b = probe_bsdf(vec3<f32>(FIX_X, FIX_Y, FIX_Z), ADJOINT);
    if (index == N - 1u) {
        out[index * PER_INDEX] = vec4<f32>(b.diffuse_prob, b.spec_prob, b.reflect_prob, b.refract_prob);
        out[index * PER_INDEX + 1u] = vec4<f32>(b.continuation, select(0.0, 1.0, b.is_delta), select(0.0, 1.0, b.valid), 0.0);
        return false;
    }
    let e = bsdf_eval(b, probe_in[index].xyz);
    out[index * PER_INDEX] = vec4<f32>(e.f, e.pdf_forward);
    out[index * PER_INDEX + 1u] = vec4<f32>(e.pdf_reverse, e.cos_gen, 0.0, 0.0);
    return false;
}
";

/// Per pair (a, b) of input directions: (f(a, b), pdf_forward(a, b)), (f(b, a),
/// pdf_forward(b, a)), (pdf_reverse(a, b), pdf_reverse(b, a)), (adjoint f(b, a)), where
/// f(x, y) has fix = x, gen = y.
const PAIRS: &str = "
fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let a = probe_in[2u * index].xyz;
    let c = probe_in[2u * index + 1u].xyz;
    let ab = bsdf_eval(probe_bsdf(a, false), normalize(c));
    let ba = bsdf_eval(probe_bsdf(c, false), normalize(a));
    let ba_adjoint = bsdf_eval(probe_bsdf(c, true), normalize(a));
    out[index * PER_INDEX] = vec4<f32>(ab.f, ab.pdf_forward);
    out[index * PER_INDEX + 1u] = vec4<f32>(ba.f, ba.pdf_forward);
    out[index * PER_INDEX + 2u] = vec4<f32>(ab.pdf_reverse, ba.pdf_reverse, 0.0, 0.0);
    out[index * PER_INDEX + 3u] = vec4<f32>(ba_adjoint.f, 0.0);
    return false;
}
";

/// A scene whose material 0 is `material` (RON): a unit sphere under a white background.
pub(crate) fn material_scene(material: &str) -> LoadedScene {
    scene(&format!(
        r#"Scene(
            camera: (position: (0, -4, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 40.0),
            materials: {{"m": {material}}},
            shapes: [Sphere(center: (0, 0, 0), radius: 1.0, material: "m")],
            lights: [Background(radiance: (1, 1, 1))],
        )"#
    ))
}

fn constants(fix: [f32; 3], adjoint: bool, part: Part) -> Vec<(&'static str, ConstValue)> {
    vec![
        ("FIX_X", ConstValue::F32(fix[0])),
        ("FIX_Y", ConstValue::F32(fix[1])),
        ("FIX_Z", ConstValue::F32(fix[2])),
        ("ADJOINT", ConstValue::Bool(adjoint)),
        ("PART", ConstValue::U32(part as u32)),
    ]
}

/// What one BSDF set-up gives: samples, their weights, and the set-up's lobe probabilities.
pub(crate) struct Sampled {
    samples: Vec<[f32; 4]>,
    weights: Vec<[f32; 3]>,
    /// Diffuse, rough specular, delta reflection, delta refraction.
    lobes: [f32; 4],
    pub(crate) continuation: f32,
    valid: bool,
}

pub(crate) fn sample(s: &LoadedScene, fix: [f32; 3], adjoint: bool, part: Part, n: u32) -> Sampled {
    let c = constants(fix, adjoint, part);
    let out = probe(s, &format!("{SETUP}{SAMPLE}"), n, 2, &[], &c);
    let setup = probe(s, &format!("{SETUP}{EVAL}"), 1, 2, &[], &c);
    Sampled {
        samples: out.iter().step_by(2).copied().collect(),
        weights: out.iter().skip(1).step_by(2).map(|w| [w[0], w[1], w[2]]).collect(),
        lobes: setup[0],
        continuation: setup[1][0],
        valid: setup[1][2] > 0.0,
    }
}

/// f and the forward pdf at each of `directions`.
pub(crate) fn eval(s: &LoadedScene, fix: [f32; 3], part: Part, directions: &[[f32; 4]]) -> Vec<([f32; 3], f32)> {
    let n = directions.len() as u32 + 1;
    let out = probe(
        s,
        &format!("{SETUP}{EVAL}"),
        n,
        2,
        directions,
        &constants(fix, false, part),
    );
    out.chunks(2)
        .take(directions.len())
        .map(|c| ([c[0][0], c[0][1], c[0][2]], c[0][3]))
        .collect()
}

fn mirror(fix: [f32; 3]) -> [f64; 3] {
    [-fix[0] as f64, -fix[1] as f64, fix[2] as f64]
}

/// Chi-square test of `material` seen from `fix` over `grid`; on the whole sphere, also the
/// pdf's integral against the samples that were lost.
fn chi2_case(what: &str, material: &str, fix: [f32; 3], grid: SphereBins) {
    chi2_part_case(what, material, Part::Whole, fix, grid);
}

/// [`chi2_case`] of a `part` of the BSDF, which must be valid.
fn chi2_part_case(what: &str, material: &str, part: Part, fix: [f32; 3], grid: SphereBins) {
    let s = material_scene(material);
    let sampled = sample(&s, fix, false, part, SAMPLES);
    assert!(sampled.valid, "{what}: {part:?} is not valid");
    let unsupported = sampled.samples.iter().filter(|s| s[3] < 0.0).count();
    assert_eq!(unsupported, 0, "{what}: samples where the pdf is 0");
    let sub = if grid.is_sphere() { SUB } else { SUB_CAP };
    let fine = grid.quadrature_points(sub);
    let coarse = grid.quadrature_points(sub / 2);
    let all: Vec<[f32; 4]> = fine.iter().chain(&coarse).copied().collect();
    let pdf: Vec<f32> = eval(&s, fix, part, &all).iter().map(|e| e.1).collect();
    let (pdf_fine, pdf_coarse) = pdf.split_at(fine.len());
    let delta = [sampled.lobes[2] as f64, sampled.lobes[3] as f64];
    let discrete: &[f64] = if grid.is_sphere() { &delta } else { &[] };
    let outcome = goodness_of_fit(&grid, &sampled.samples, pdf_fine, sub, discrete);
    eprintln!("{what}: {outcome}, lobes {:?}", sampled.lobes);
    assert!(
        outcome.passes(significance(CHI2_TESTS)),
        "{what}: sampled directions do not follow the pdf: {outcome}"
    );
    if !grid.is_sphere() {
        return;
    }
    // The midpoint rule's error falls 4x per halving of the step, so the difference from the
    // coarser grid bounds it (it is about a third of that difference).
    let integral = outcome.pdf_integral;
    let coarse_integral: f64 = grid.integrate(pdf_coarse, sub / 2).iter().sum();
    let quadrature = (integral - coarse_integral).abs() + 1e-4;
    let total = integral + delta[0] + delta[1];
    assert!(
        total <= 1.0 + quadrature,
        "{what}: the pdf integrates to {integral} and the delta lobes have {delta:?}: more than 1"
    );
    // Samples are lost (none returned) with probability 1 - total; 4 binomial standard
    // errors plus the quadrature error.
    let n = sampled.samples.len() as f64;
    let lost = sampled.samples.iter().filter(|s| s[3] == 0.0).count() as f64 / n;
    let expected = (1.0 - total).max(0.0);
    let se = (expected.max(1.0 / n) * (1.0 - expected) / n).sqrt();
    assert!(
        (lost - expected).abs() <= 4.0 * se + quadrature,
        "{what}: {lost} of the samples are lost, but the pdf leaves {expected} (quadrature error {quadrature})"
    );
}

fn sphere() -> SphereBins {
    SphereBins::sphere(24, 48)
}

const OBLIQUE: [f32; 3] = [0.6, 0.2, 0.7];
const BELOW: [f32; 3] = [0.5, -0.3, -0.6];

#[test]
fn chi2_smallvcm_diffuse() {
    chi2_case("diffuse", "(diffuse: (0.8, 0.6, 0.4))", OBLIQUE, sphere());
}

#[test]
fn chi2_smallvcm_phong() {
    let m = "(diffuse: (0.2, 0.2, 0.2), phong: (0.6, 0.6, 0.6), phong_exponent: 30.0)";
    chi2_case("phong", m, OBLIQUE, sphere());
}

#[test]
fn chi2_smallvcm_glass() {
    let m = "(mirror: (1, 1, 1), ior: 1.6)";
    chi2_case("glass outside", m, OBLIQUE, sphere());
    chi2_case("glass inside", m, BELOW, sphere());
}

#[test]
fn a_pbr_material_without_specular_layer_is_the_lambertian_of_its_base_colour() {
    // Index of refraction 1, no metal, no transmission: KHR_materials_specular 0, Mitsuba's
    // textured diffuse. Its f and pdf must be the Lambertian lobe's, to float rounding.
    let directions = [
        [0.3f32, -0.2, 0.93, 0.0],
        [-0.7, 0.1, 0.2, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.5, 0.5, -0.5, 0.0],
    ];
    let lambertian = eval(
        &material_scene("(diffuse: (0.8, 0.6, 0.4))"),
        OBLIQUE,
        Part::Whole,
        &directions,
    );
    let layerless = "(pbr: (base_color: (0.8, 0.6, 0.4), roughness: 0.3, ior: 1.0))";
    let pbr = eval(&material_scene(layerless), OBLIQUE, Part::Whole, &directions);
    for ((l, p), d) in lambertian.iter().zip(&pbr).zip(&directions) {
        for c in 0..3 {
            assert!(
                (l.0[c] - p.0[c]).abs() <= 1e-6 * l.0[c].abs().max(1e-6),
                "{d:?}: f {:?} against {:?}",
                p.0,
                l.0
            );
        }
        assert!(
            (l.1 - p.1).abs() <= 1e-6 * l.1.abs().max(1e-6),
            "{d:?}: pdf {} against {}",
            p.1,
            l.1
        );
    }
    // With a specular layer (index 1.5) it stays the PBR model: at the mirror direction its
    // glossy lobe adds several times the Lambertian's value.
    let n = (OBLIQUE[0] * OBLIQUE[0] + OBLIQUE[1] * OBLIQUE[1] + OBLIQUE[2] * OBLIQUE[2]).sqrt();
    let mirrored = [[-OBLIQUE[0] / n, -OBLIQUE[1] / n, OBLIQUE[2] / n, 0.0]];
    let layered = "(pbr: (base_color: (0.8, 0.6, 0.4), roughness: 0.3, ior: 1.5))";
    let glossy = eval(&material_scene(layered), OBLIQUE, Part::Whole, &mirrored);
    assert!(
        glossy[0].0[2] > 2.0 * lambertian[0].0[2],
        "{:?} against {:?}",
        glossy[0].0,
        lambertian[0].0
    );
}

#[test]
fn chi2_pbr_rough_plastic() {
    let m = "(pbr: (base_color: (0.8, 0.8, 0.8), roughness: 1.0))";
    chi2_case("rough plastic", m, OBLIQUE, sphere());
}

#[test]
fn chi2_pbr_glossy_plastic() {
    let m = "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.3))";
    chi2_case("glossy plastic", m, OBLIQUE, sphere());
}

#[test]
fn chi2_beckmann() {
    // Beckmann's visible normals (a CDF inverted numerically) against its pdf: metals from
    // oblique and near-normal incidence, a narrow lobe in a cap around the mirror direction,
    // a rough dielectric (reflection and refraction) and a rough plastic.
    for (roughness, fix) in [(1.0, OBLIQUE), (0.5, [0.0, 0.3, 0.95]), (0.3, [0.9, 0.0, 0.2])] {
        let m = format!(
            "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: {roughness}, distribution: Beckmann))"
        );
        chi2_case(&format!("Beckmann metal {roughness}"), &m, fix, sphere());
    }
    let alpha = 0.01f64;
    let grid = SphereBins::cap(mirror(OBLIQUE), (10.0 * alpha).cos(), 12, 24);
    let m = "(pbr: (metallic: 1.0, roughness: 0.1, distribution: Beckmann))";
    chi2_case("Beckmann metal 0.1", m, OBLIQUE, grid);
    let m = "(pbr: (roughness: 0.5, transmission: 1.0, distribution: Beckmann))";
    chi2_case("Beckmann dielectric", m, OBLIQUE, sphere());
    let m = "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.4, distribution: Beckmann, plastic: Some((nonlinear: true))))";
    chi2_case("Beckmann rough plastic", m, OBLIQUE, sphere());
}

#[test]
fn chi2_mitsuba_rough_plastic() {
    // Mitsuba's rough plastic: its diffuse lobe weighed by its coating's tabulated
    // transmittance, at an oblique and a grazing direction.
    let m = "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.5, ior: 1.8, masking: Separable, plastic: Some((nonlinear: false))))";
    chi2_case("GGX rough plastic", m, OBLIQUE, sphere());
    chi2_case("GGX rough plastic, grazing", m, [0.99, 0.0, 0.1], sphere());
}

#[test]
fn chi2_pbr_metal() {
    for (roughness, fix) in [(1.0, OBLIQUE), (0.5, [0.0, 0.3, 0.95]), (0.2, OBLIQUE)] {
        let m = format!("(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: {roughness}))");
        chi2_case(&format!("metal {roughness}"), &m, fix, sphere());
    }
}

#[test]
fn chi2_pbr_narrow_metal() {
    // Lobes a few alpha wide: tested in a cap of 10 alpha around the mirror direction.
    for roughness in [0.1f32, 0.05] {
        let alpha = (roughness * roughness) as f64;
        let m = format!("(pbr: (base_color: (1, 1, 1), metallic: 1.0, roughness: {roughness}))");
        let grid = SphereBins::cap(mirror(OBLIQUE), (10.0 * alpha).cos(), 12, 24);
        chi2_case(&format!("metal {roughness}"), &m, OBLIQUE, grid);
    }
}

#[test]
fn chi2_pbr_rough_dielectric() {
    let m = "(pbr: (base_color: (1, 1, 1), roughness: 0.4, transmission: 1.0, ior: 1.5))";
    chi2_case("rough glass outside", m, OBLIQUE, sphere());
    chi2_case("rough glass inside", m, BELOW, sphere());
}

#[test]
fn chi2_pbr_smooth_dielectric() {
    let m = "(pbr: (base_color: (1, 1, 1), roughness: 0.0, transmission: 1.0, ior: 1.5))";
    chi2_case("smooth glass outside", m, OBLIQUE, sphere());
    chi2_case("smooth glass inside", m, BELOW, sphere());
}

/// A white thin-walled glass of index 1.5 and `roughness`.
fn thin_glass(roughness: f32) -> String {
    format!("(pbr: (base_color: (1, 1, 1), roughness: {roughness}, transmission: 1.0, ior: 1.5, thin_walled: true))")
}

#[test]
fn chi2_pbr_thin_walled() {
    for roughness in [0.0, 0.4] {
        let m = thin_glass(roughness);
        chi2_case(&format!("thin glass {roughness} outside"), &m, OBLIQUE, sphere());
        chi2_case(&format!("thin glass {roughness} inside"), &m, BELOW, sphere());
    }
    // A narrow lobe: tested in a cap of 10 alpha around the straight-through direction.
    let alpha = 0.1f64 * 0.1;
    let through = OBLIQUE.map(|c| -c as f64);
    let grid = SphereBins::cap(through, (10.0 * alpha).cos(), 12, 24);
    chi2_case("thin glass 0.1 through", &thin_glass(0.1), OBLIQUE, grid);
}

#[test]
fn smooth_thin_walled_glass_lets_light_through_unbent_with_the_slab_transmittance() {
    // Delta refraction leaves along -fix with weight 1 (white, radiance: no eta^2, as no
    // medium changes), picked with probability 1 - R', R' = 2R / (1 + R) the slab's
    // reflectance: within 4 binomial standard errors of 200,000 samples.
    let s = material_scene(&thin_glass(0.0));
    for fix in [OBLIQUE, BELOW] {
        let n = (fix[0] * fix[0] + fix[1] * fix[1] + fix[2] * fix[2]).sqrt();
        let through = fix.map(|c| -c / n);
        let sampled = sample(&s, fix, false, Part::Whole, SAMPLES);
        let mut transmitted = 0;
        for (d, w) in sampled.samples.iter().zip(&sampled.weights) {
            assert!(d[3] == 2.0 || d[3] == 3.0, "{fix:?}: a sample of kind {}", d[3]);
            assert!(w.iter().all(|&c| (c - 1.0).abs() < 1e-5), "{fix:?}: weight {w:?}");
            if d[3] == 3.0 {
                transmitted += 1;
                assert!(
                    (0..3).all(|c| (d[c] - through[c]).abs() < 1e-5),
                    "{fix:?}: {d:?} against {through:?}"
                );
            }
        }
        let r = fresnel((fix[2] / n).abs() as f64, 1.5);
        let expected = 1.0 - 2.0 * r / (1.0 + r);
        let share = transmitted as f64 / SAMPLES as f64;
        let se = (expected * (1.0 - expected) / SAMPLES as f64).sqrt();
        eprintln!("{fix:?}: {share} transmitted, slab {expected} +- {se}");
        assert!(
            (share - expected).abs() <= 4.0 * se,
            "{fix:?}: {share} transmitted, the slab lets {expected} through (+- {se})"
        );
    }
}

#[test]
fn chi2_pbr_mixture() {
    // Every lobe at once: metal, dielectric reflection, diffuse and transmission.
    let m = "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5))";
    chi2_case("mixture outside", m, OBLIQUE, sphere());
}

/// Diffuse, Phong and glass lobes at once.
const SMALLVCM_MIX: &str =
    "(diffuse: (0.5, 0.4, 0.3), phong: (0.3, 0.3, 0.3), phong_exponent: 20.0, mirror: (0.8, 0.8, 0.8), ior: 1.5)";
/// Every glTF lobe at once, rough.
const PBR_MIX: &str = "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5))";
/// A smooth glTF dielectric over a diffuse base: its glossy part is delta.
const PBR_SMOOTH_MIX: &str = "(pbr: (base_color: (0.7, 0.8, 0.9), roughness: 0.0, transmission: 0.5))";
/// Every glTF lobe at once, rough, transmission through a thin wall.
const PBR_THIN_MIX: &str =
    "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5, thin_walled: true))";

#[test]
fn chi2_smallvcm_parts() {
    chi2_part_case("diffuse part", SMALLVCM_MIX, Part::Diffuse, OBLIQUE, sphere());
    chi2_part_case("glossy part", SMALLVCM_MIX, Part::Glossy, OBLIQUE, sphere());
}

#[test]
fn chi2_pbr_parts() {
    chi2_part_case("mixture diffuse part", PBR_MIX, Part::Diffuse, OBLIQUE, sphere());
    chi2_part_case("mixture glossy part outside", PBR_MIX, Part::Glossy, OBLIQUE, sphere());
    chi2_part_case("mixture glossy part inside", PBR_MIX, Part::Glossy, BELOW, sphere());
    chi2_part_case("smooth diffuse part", PBR_SMOOTH_MIX, Part::Diffuse, OBLIQUE, sphere());
    chi2_part_case("smooth glossy part", PBR_SMOOTH_MIX, Part::Glossy, OBLIQUE, sphere());
    chi2_part_case(
        "thin glossy part outside",
        PBR_THIN_MIX,
        Part::Glossy,
        OBLIQUE,
        sphere(),
    );
    chi2_part_case("thin glossy part inside", PBR_THIN_MIX, Part::Glossy, BELOW, sphere());
}

/// Mean and standard error of the albedo estimate f cos / pdf (largest channel).
fn albedo(sampled: &Sampled) -> (f64, f64) {
    let v: Vec<f64> = sampled
        .weights
        .iter()
        .map(|w| w.iter().copied().fold(0.0f32, f32::max) as f64)
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Mean and standard error of the weights f cos / pdf, per channel.
pub(crate) fn mean_weight(sampled: &Sampled) -> ([f64; 3], [f64; 3]) {
    let n = sampled.weights.len() as f64;
    let mean: [f64; 3] = std::array::from_fn(|c| sampled.weights.iter().map(|w| w[c] as f64).sum::<f64>() / n);
    let se = std::array::from_fn(|c| {
        let var = sampled
            .weights
            .iter()
            .map(|w| (w[c] as f64 - mean[c]).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        (var / n).sqrt()
    });
    (mean, se)
}

#[test]
fn white_furnace() {
    // White metals reflect at most 1. Single-scattering GGX loses the light that would
    // scatter again between microfacets, and with it the reflections its long-tailed normal
    // distribution sends below the horizon: next to nothing at roughness 0.05; at alpha 1,
    // half the visible normals at normal incidence are tilted beyond 45 degrees, and the loss
    // reaches 60-70% (Heitz et al. 2016 show the same for their single-scattering baseline).
    // The lower bounds are those losses with a margin: they catch a lobe that loses more.
    // A white dielectric with transmission conserves energy (adjoint form: integrated over
    // the directions light leaves in) up to the same loss; a smooth one exactly; thin-walled
    // ones alike (their transmission is mirrored reflection). The diffuse
    // base of plastic loses 1 - F_avg (9% at ior 1.5). Mitsuba's rough plastic loses what its
    // coating masks (by Mitsuba's tables, a white base sends back 0.93 of the light arriving at
    // normal incidence at Beckmann alpha 0.1, ior 1.5, 0.51 at GGX alpha 0.5). The continuation
    // probability is at least the albedo.
    let normal = [0.0, 0.0, 1.0];
    let grazing = [0.94, 0.0, 0.342]; // 70 degrees
    let white_rough_plastic = |roughness: f32, distribution: &str| {
        format!(
            "(pbr: (roughness: {roughness}, distribution: {distribution}, masking: Separable, plastic: Some((nonlinear: false))))"
        )
    };
    let beckmann_plastic = white_rough_plastic(0.1f32.sqrt(), "Beckmann");
    let ggx_plastic = white_rough_plastic(0.5f32.sqrt(), "Ggx");
    let cases: &[(&str, [f32; 3], f64)] = &[
        (&beckmann_plastic, normal, 0.95),
        (&beckmann_plastic, grazing, 0.8),
        (&ggx_plastic, normal, 0.5),
        (&ggx_plastic, grazing, 0.35),
        ("(pbr: (metallic: 1.0, roughness: 0.05))", normal, 0.999),
        ("(pbr: (metallic: 1.0, roughness: 0.05))", grazing, 0.999),
        ("(pbr: (metallic: 1.0, roughness: 0.5))", normal, 0.88),
        ("(pbr: (metallic: 1.0, roughness: 0.5))", grazing, 0.8),
        ("(pbr: (metallic: 1.0, roughness: 1.0))", normal, 0.25),
        ("(pbr: (metallic: 1.0, roughness: 1.0))", grazing, 0.45),
        ("(pbr: (roughness: 0.0, transmission: 1.0))", OBLIQUE, 1.0),
        ("(pbr: (roughness: 0.0, transmission: 1.0))", BELOW, 1.0),
        ("(pbr: (roughness: 0.3, transmission: 1.0))", OBLIQUE, 0.95),
        ("(pbr: (roughness: 0.3, transmission: 1.0))", BELOW, 0.95),
        (
            "(pbr: (roughness: 0.0, transmission: 1.0, thin_walled: true))",
            OBLIQUE,
            1.0,
        ),
        (
            "(pbr: (roughness: 0.0, transmission: 1.0, thin_walled: true))",
            BELOW,
            1.0,
        ),
        (
            "(pbr: (roughness: 0.3, transmission: 1.0, thin_walled: true))",
            OBLIQUE,
            0.95,
        ),
        (
            "(pbr: (roughness: 0.3, transmission: 1.0, thin_walled: true))",
            BELOW,
            0.95,
        ),
        ("(pbr: (roughness: 0.5))", OBLIQUE, 0.85),
        // Beckmann's single scattering loses less than GGX's (its tail is shorter).
        (
            "(pbr: (metallic: 1.0, roughness: 0.05, distribution: Beckmann))",
            grazing,
            0.999,
        ),
        (
            "(pbr: (metallic: 1.0, roughness: 0.5, distribution: Beckmann))",
            normal,
            0.9,
        ),
        (
            "(pbr: (metallic: 1.0, roughness: 0.5, distribution: Beckmann))",
            grazing,
            0.8,
        ),
        (
            "(pbr: (roughness: 0.3, transmission: 1.0, distribution: Beckmann))",
            OBLIQUE,
            0.95,
        ),
        (
            "(pbr: (roughness: 0.3, transmission: 1.0, distribution: Beckmann))",
            BELOW,
            0.95,
        ),
    ];
    for &(material, fix, lower) in cases {
        let s = material_scene(material);
        let sampled = sample(&s, fix, true, Part::Whole, 100_000);
        let (mean, se) = albedo(&sampled);
        eprintln!(
            "{material} from {fix:?}: albedo {mean:.5} +- {se:.5}, continuation {}",
            sampled.continuation
        );
        assert!(
            mean <= 1.0 + 4.0 * se + 1e-5,
            "{material} from {fix:?}: albedo {mean} +- {se} above 1"
        );
        assert!(
            mean >= lower - 4.0 * se - 1e-5,
            "{material} from {fix:?}: albedo {mean} +- {se} below {lower}"
        );
        assert!(
            sampled.continuation as f64 >= mean - 4.0 * se - 1e-5,
            "{material} from {fix:?}: continuation {} below the albedo {mean}",
            sampled.continuation
        );
    }
}

/// The unpolarised Fresnel reflectance of a conductor of index eta + i k at incidence cosine
/// `c`, from the s- and p-polarised amplitudes of complex arithmetic (independent of the
/// shader's real-valued form).
fn conductor_reflectance(c: f64, eta: f64, k: f64) -> f64 {
    // Complex numbers as (re, im).
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: (f64, f64), b: (f64, f64)| {
        let d = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: (f64, f64)| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        (((r + a.0) / 2.0).sqrt(), ((r - a.0) / 2.0).sqrt().copysign(a.1))
    };
    let n = (eta, k);
    let n2 = mul(n, n);
    // cos of the transmitted angle: sqrt(1 - sin^2 / n^2).
    let s2 = div((1.0 - c * c, 0.0), n2);
    let ct = sqrt((1.0 - s2.0, -s2.1));
    let nct = mul(n, ct);
    let nc = (n.0 * c, n.1 * c);
    let rs = div((c - nct.0, -nct.1), (c + nct.0, nct.1));
    let rp = div((nc.0 - ct.0, nc.1 - ct.1), (nc.0 + ct.0, nc.1 + ct.1));
    0.5 * (rs.0 * rs.0 + rs.1 * rs.1 + rp.0 * rp.0 + rp.1 * rp.1)
}

#[test]
fn smooth_conductors_reflect_their_exact_fresnel_times_their_tint() {
    // Mitsuba's aluminium (VeachAjar's floor) tinted 0.8, 0.6, 0.4: the delta reflection's
    // weight f cos / pdf is the tint times the conductor's reflectance at the angle, exactly.
    let (eta, k) = ([1.65746, 0.880369, 0.521229], [9.22387, 6.26952, 4.837]);
    let tint = [0.8, 0.6, 0.4];
    let m = format!(
        "(pbr: (base_color: {tint:?}, metallic: 1.0, roughness: 0.0, conductor: Some((eta: {eta:?}, k: {k:?}))))"
    )
    .replace('[', "(")
    .replace(']', ")");
    let s = material_scene(&m);
    for cos in [1.0f64, 0.5, 0.1] {
        let fix = [(1.0 - cos * cos).sqrt() as f32, 0.0, cos as f32];
        let (mean, _) = mean_weight(&sample(&s, fix, false, Part::Whole, 1000));
        for c in 0..3 {
            let want = tint[c] * conductor_reflectance(cos, eta[c], k[c]);
            assert!(
                (mean[c] - want).abs() < 1e-4 * want,
                "cos {cos} channel {c}: {} where the conductor reflects {want}",
                mean[c]
            );
        }
    }
}

#[test]
fn white_plastic_reflects_everything() {
    // Mitsuba's smooth plastic with a white base (linear): the coating reflects F(cos_o), and
    // the base's light that leaves, 1 - F_dr(outside), over the ior^2 (1 - F_dr(inside)) its
    // internal scattering adds up to, is all the rest, 1 - F(cos_o) (F_dr's identity). The
    // fits of F_dr Mitsuba uses are within 0.1% of the integrals: 0.2% of the albedo is
    // allowed for them. Without the internal scattering the albedo is 0.91 (ior 1.5).
    for ior in [1.5, 2.0] {
        let m = format!("(pbr: (roughness: 0.0, ior: {ior}, plastic: Some((nonlinear: false))))");
        for fix in [[0.0, 0.0, 1.0], OBLIQUE, [0.94, 0.0, 0.342]] {
            let sampled = sample(&material_scene(&m), fix, false, Part::Whole, 100_000);
            let (mean, se) = albedo(&sampled);
            eprintln!("plastic ior {ior} from {fix:?}: albedo {mean:.5} +- {se:.5}");
            assert!(
                (mean - 1.0).abs() < 0.002 + 4.0 * se,
                "plastic ior {ior} from {fix:?}: albedo {mean} +- {se} is not 1"
            );
        }
    }
}

#[test]
fn parts_share_the_albedo_and_continue_with_at_least_their_own() {
    // f = f(diffuse part) + f(glossy part) and each part samples its own lobes without bias,
    // so the albedos of the parts (f cos / pdf, light leaving in the sampled directions) add up
    // to the whole's; a part's continuation bounds its albedo up to 1 (SmallVCM's glass
    // reflects and transmits everything, so the mix with Phong reflects more than 1).
    let grazing = [0.94, 0.0, 0.342];
    let metal = "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 0.5, roughness: 0.3))";
    for material in [SMALLVCM_MIX, PBR_MIX, PBR_SMOOTH_MIX, PBR_THIN_MIX, metal] {
        let s = material_scene(material);
        for fix in [OBLIQUE, BELOW, grazing] {
            let n = 100_000;
            let (whole, whole_se) = mean_weight(&sample(&s, fix, true, Part::Whole, n));
            let mut sum = [0.0; 3];
            let mut var = whole_se.map(|e| e * e);
            for part in [Part::Diffuse, Part::Glossy] {
                let sampled = sample(&s, fix, true, part, n);
                let (mean, se) = mean_weight(&sampled);
                let (largest, largest_se) = albedo(&sampled);
                eprintln!(
                    "{material} from {fix:?}, {part:?}: albedo {mean:.4?}, continuation {}",
                    sampled.continuation
                );
                assert!(
                    sampled.continuation as f64 >= (largest - 4.0 * largest_se).min(1.0) - 1e-5,
                    "{material} from {fix:?}, {part:?}: continuation {} below the albedo {largest}",
                    sampled.continuation
                );
                for c in 0..3 {
                    sum[c] += mean[c];
                    var[c] += se[c] * se[c];
                }
            }
            for c in 0..3 {
                assert!(
                    (whole[c] - sum[c]).abs() <= 4.0 * var[c].sqrt() + 1e-5,
                    "{material} from {fix:?}: the parts' albedos add up to {sum:?}, the whole's is {whole:?}"
                );
            }
        }
    }
}

/// Random unit directions (SplitMix64), each with z of the sign `side` gives (0 any).
pub(crate) fn directions(n: usize, seed: u64, side: f32) -> Vec<[f32; 4]> {
    let mut rng = crate::common::SplitMix64(seed);
    let mut next = move || rng.next_f64();
    (0..n)
        .map(|_| {
            let z = 1.0 - 2.0 * next();
            let phi = std::f64::consts::TAU * next();
            let r = (1.0 - z * z).sqrt();
            let z = if side == 0.0 { z } else { z.abs() * side as f64 };
            [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32, 0.0]
        })
        .collect()
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 2e-3 * a.abs().max(b.abs()) + 1e-6
}

/// Whether the refraction between `a` (in index `ea`) and `b` (in `eb`) meets its microfacet
/// within 3 degrees of grazing on either side. There the Fresnel transmittance 1 - F is
/// proportional to that cosine c, which f32 gets from the other side's through
/// 1 - sin^2 (about 1e-7 absolute error in c^2): at c = 0.0055 the two sides' values differed
/// by 0.3%, past `close`'s tolerance, with the logic right (checked in f64).
fn grazes_its_microfacet(a: [f32; 4], b: [f32; 4], ea: f32, eb: f32) -> bool {
    if a[2] * b[2] >= 0.0 {
        return false;
    }
    let h: [f64; 3] = std::array::from_fn(|i| (ea * a[i] + eb * b[i]) as f64);
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let cos = |d: [f32; 4]| (0..3).map(|i| d[i] as f64 * h[i]).sum::<f64>().abs() / len;
    cos(a).min(cos(b)) < 0.05
}

/// Reciprocity and pdf consistency of `part` of the BSDF on random pairs of directions: `a`
/// from `side_a`, `b` from `side_b`.
fn check_pairs(material: &str, part: Part, side_a: f32, side_b: f32, ior: f32) {
    let what = format!("{material} ({part:?})");
    let s = material_scene(material);
    let a = directions(2000, 11, side_a);
    let b = directions(2000, 12, side_b);
    let input: Vec<[f32; 4]> = a.iter().zip(&b).flat_map(|(x, y)| [*x, *y]).collect();
    let part_constant = [("PART", ConstValue::U32(part as u32))];
    let out = probe(
        &s,
        &format!("{SETUP}{PAIRS}"),
        a.len() as u32,
        4,
        &input,
        &part_constant,
    );
    let mut nonzero = 0;
    for (k, o) in out.chunks(4).enumerate() {
        let (ab, ba, rev, ba_adj) = (o[0], o[1], o[2], o[3]);
        let eta = |d: &[f32; 4]| if d[2] > 0.0 { 1.0 } else { ior };
        let (ea, eb) = (eta(&a[k]), eta(&b[k]));
        if grazes_its_microfacet(a[k], b[k], ea, eb) {
            continue;
        }
        for c in 0..3 {
            // Radiance BSDFs satisfy f(a, b) / eta_a^2 = f(b, a) / eta_b^2 (fix = a: eta_a is
            // the index on the side the radiance leaves to); the adjoint swaps the arguments.
            assert!(
                close(ab[c] / (ea * ea), ba[c] / (eb * eb)),
                "{what}: f({:?}, {:?}) = {} but f back = {}",
                a[k],
                b[k],
                ab[c],
                ba[c]
            );
            assert!(
                close(ab[c], ba_adj[c]),
                "{what}: f({:?}, {:?}) = {} but the adjoint f back = {}",
                a[k],
                b[k],
                ab[c],
                ba_adj[c]
            );
        }
        assert!(
            close(rev[0], ba[3]) && close(rev[1], ab[3]),
            "{what}: pdfs ({:?}, {:?}): forward {} reverse {}, back: forward {} reverse {}",
            a[k],
            b[k],
            ab[3],
            rev[0],
            ba[3],
            rev[1]
        );
        nonzero += (ab[3] > 0.0) as u32;
    }
    // Refraction joins only directions more than acos(1 / eta) apart: about a fifth of the
    // random pairs on opposite sides.
    assert!(nonzero > 300, "{what}: only {nonzero} pairs with a nonzero pdf");
}

#[test]
fn reflection_is_reciprocal_and_pdfs_are_consistent() {
    for m in [
        "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: 0.3))",
        "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.5))",
        "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5))",
        "(diffuse: (0.2, 0.3, 0.4), phong: (0.5, 0.5, 0.5), phong_exponent: 20.0)",
        "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: 0.3, distribution: Beckmann))",
        "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: 0.3, masking: Separable))",
        "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.5, distribution: Beckmann, plastic: Some((nonlinear: true))))",
    ] {
        check_pairs(m, Part::Whole, 1.0, 1.0, 1.5);
    }
    let glass = "(pbr: (base_color: (1, 1, 1), metallic: 0.2, roughness: 0.4, transmission: 0.8, ior: 1.5))";
    check_pairs(glass, Part::Whole, -1.0, -1.0, 1.5);
}

#[test]
fn refraction_is_reciprocal_up_to_eta_squared_and_pdfs_are_consistent() {
    let glass = "(pbr: (base_color: (0.9, 0.8, 1.0), metallic: 0.2, roughness: 0.4, transmission: 0.8, ior: 1.5))";
    check_pairs(glass, Part::Whole, 1.0, -1.0, 1.5);
    check_pairs(glass, Part::Whole, -1.0, 1.0, 1.5);
    let beckmann = "(pbr: (roughness: 0.8, transmission: 1.0, ior: 1.5, distribution: Beckmann))";
    check_pairs(beckmann, Part::Whole, 1.0, -1.0, 1.5);
}

#[test]
fn thin_walled_transmission_is_reciprocal_and_pdfs_are_consistent() {
    // Through a thin wall the medium does not change: f(a, b) = f(b, a) on every pair of
    // sides (an index of 1 on both sides for check_pairs' eta^2).
    let glass = "(pbr: (base_color: (0.9, 0.8, 1.0), metallic: 0.2, roughness: 0.4, transmission: 0.8, ior: 1.5, thin_walled: true))";
    for (side_a, side_b) in [(1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0)] {
        check_pairs(glass, Part::Whole, side_a, side_b, 1.0);
    }
    check_pairs(PBR_THIN_MIX, Part::Glossy, 1.0, -1.0, 1.0);
    check_pairs(PBR_THIN_MIX, Part::Diffuse, 1.0, 1.0, 1.0);
}

#[test]
fn parts_are_reciprocal_and_their_pdfs_consistent() {
    check_pairs(PBR_MIX, Part::Diffuse, 1.0, 1.0, 1.5);
    check_pairs(PBR_MIX, Part::Glossy, 1.0, 1.0, 1.5);
    check_pairs(PBR_MIX, Part::Glossy, 1.0, -1.0, 1.5);
    check_pairs(PBR_MIX, Part::Glossy, -1.0, 1.0, 1.5);
    let smallvcm = "(diffuse: (0.2, 0.3, 0.4), phong: (0.5, 0.5, 0.5), phong_exponent: 20.0)";
    check_pairs(smallvcm, Part::Diffuse, 1.0, 1.0, 1.5);
    check_pairs(smallvcm, Part::Glossy, 1.0, 1.0, 1.5);
}

/// A random material of either model, with the parameters the checks need.
struct RandomMaterial {
    ron: String,
    pbr: bool,
    /// Lambertian reflectance (SmallVCM) or base colour (glTF).
    diffuse: [f64; 3],
    /// SmallVCM: whether there is a Phong lobe, and a mirror or glass lobe.
    phong: bool,
    specular: bool,
    metallic: f64,
    roughness: f64,
    transmission: f64,
    ior: f64,
    /// glTF: transmission through a thin wall.
    thin_walled: bool,
}

impl RandomMaterial {
    /// Lobes present or absent at random, colours in [0.05, 0.95]; glTF roughness 0 or 0.02
    /// (smooth: alpha below 1e-3) half the time, metallic and transmission 0 or 1 two thirds
    /// of the time, thin-walled half the time.
    fn new(pbr: bool, rng: &mut crate::common::SplitMix64) -> Self {
        let u: [f64; 15] = std::array::from_fn(|_| rng.next_f64());
        let colour = |k: usize, on: bool| {
            let c = [u[k], u[k + 1], u[k + 2]].map(|x| 0.05 + 0.9 * x);
            if on { c } else { [0.0; 3] }
        };
        let rgb = |c: [f64; 3]| format!("({}, {}, {})", c[0], c[1], c[2]);
        if pbr {
            let metallic = [0.0, 1.0, u[3]][(u[4] * 3.0) as usize];
            let rough = 0.1 + 0.9 * u[5];
            let roughness = [0.0, 0.02, rough, rough][(u[6] * 4.0) as usize];
            let transmission = [0.0, 1.0, u[7]][(u[8] * 3.0) as usize];
            let ior = 1.2 + 0.8 * u[9];
            let diffuse = colour(0, true);
            let thin_walled = u[14] < 0.5;
            let ron = format!(
                "(pbr: (base_color: {}, metallic: {metallic}, roughness: {roughness}, transmission: {transmission}, ior: {ior}, thin_walled: {thin_walled}))",
                rgb(diffuse)
            );
            RandomMaterial {
                ron,
                pbr,
                diffuse,
                phong: false,
                specular: false,
                metallic,
                roughness,
                transmission,
                ior,
                thin_walled,
            }
        } else {
            let diffuse = colour(0, u[9] < 0.75);
            let phong = u[10] < 0.5;
            // A third without a specular lobe, a third mirrors, a third glass.
            let specular = u[11] < 2.0 / 3.0;
            let ior = if u[11] < 1.0 / 3.0 { 1.2 + 0.8 * u[12] } else { -1.0 };
            let ron = format!(
                "(diffuse: {}, phong: {}, phong_exponent: {}, mirror: {}, ior: {ior})",
                rgb(diffuse),
                rgb(colour(3, phong)),
                1.0 + 99.0 * u[13],
                rgb(colour(6, specular)),
            );
            RandomMaterial {
                ron,
                pbr,
                diffuse,
                phong,
                specular,
                metallic: 0.0,
                roughness: 0.0,
                transmission: 0.0,
                ior,
                thin_walled: false,
            }
        }
    }

    /// The diffuse lobe's value for fix `a` and gen `b` (z-up).
    fn diffuse(&self, a: &[f32; 4], b: &[f32; 4]) -> [f64; 3] {
        if a[2] <= 0.0 || b[2] <= 0.0 {
            return [0.0; 3];
        }
        let scale = if self.pbr {
            self.diffuse_share(a) * (1.0 - self.fresnel(b[2] as f64))
        } else {
            1.0
        };
        self.diffuse.map(|c| c * scale / std::f64::consts::PI)
    }

    /// The share of the diffuse colour the diffuse lobe reflects at most from fix `a`: glTF's
    /// (1 - metallic) (1 - transmission) (1 - F), all of it in SmallVCM's.
    fn diffuse_share(&self, a: &[f32; 4]) -> f64 {
        if !self.pbr {
            return 1.0;
        }
        let f = self.fresnel(a[2] as f64);
        (1.0 - self.metallic) * (1.0 - self.transmission) * (1.0 - f)
    }

    /// glTF's dielectric reflectance seen from outside at cosine `cos` > 0: the interface's,
    /// or with transmission through a thin wall the slab's, 2R / (1 + R).
    fn fresnel(&self, cos: f64) -> f64 {
        let r = fresnel(cos, self.ior.max(1.001));
        if self.thin_walled && self.transmission > 0.0 {
            2.0 * r / (1.0 + r)
        } else {
            r
        }
    }
}

/// Fresnel reflectance of a smooth dielectric of index `ior`, seen from outside at cosine
/// `cos` > 0.
fn fresnel(cos: f64, ior: f64) -> f64 {
    let eta = 1.0 / ior;
    let sin_t2 = eta * eta * (1.0 - cos * cos);
    let cos_t = (1.0 - sin_t2).sqrt();
    let parallel = (cos - eta * cos_t) / (cos + eta * cos_t);
    let perpendicular = (eta * cos - cos_t) / (eta * cos + cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// Per pair of directions (a, b), a's w the index of the material: (f, pdf_forward) with
/// fix = a and gen = b of the whole BSDF, of its diffuse part and of its glossy part; the
/// whole's probabilities of its diffuse lobe and of the others, with bsdf_has_diffuse and
/// bsdf_has_glossy; the diffuse part's (valid, is_delta, continuation) with the whole's
/// continuation; the glossy part's (valid, is_delta, continuation) with the whole's valid.
const PARTS: &str = "
fn probe_flag(b: bool) -> f32 {
    return select(0.0, 1.0, b);
}

fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let a = probe_in[2u * index];
    let gen = normalize(probe_in[2u * index + 1u].xyz);
    let n = vec3<f32>(0.0, 0.0, 1.0);
    let b = bsdf_setup(material_at(u32(a.w), vec2<f32>(0.0)), n, n, normalize(a.xyz));
    let d = bsdf_diffuse_part(b);
    let g = bsdf_glossy_part(b);
    let whole = bsdf_eval(b, gen);
    let ed = bsdf_eval(d, gen);
    let eg = bsdf_eval(g, gen);
    let others = b.phong_prob + b.spec_prob + b.reflect_prob + b.refract_prob;
    let o = index * PER_INDEX;
    out[o] = vec4<f32>(whole.f, whole.pdf_forward);
    out[o + 1u] = vec4<f32>(ed.f, ed.pdf_forward);
    out[o + 2u] = vec4<f32>(eg.f, eg.pdf_forward);
    out[o + 3u] = vec4<f32>(b.diffuse_prob, others, probe_flag(bsdf_has_diffuse(b)), probe_flag(bsdf_has_glossy(b)));
    out[o + 4u] = vec4<f32>(probe_flag(d.valid), probe_flag(d.is_delta), d.continuation, b.continuation);
    out[o + 5u] = vec4<f32>(probe_flag(g.valid), probe_flag(g.is_delta), g.continuation, probe_flag(b.valid));
    return false;
}
";

/// Whether `a` and `b` agree to float rounding.
fn rounding(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-5 * a.abs().max(b.abs()) + 1e-30
}

#[test]
fn parts_add_up_to_the_whole_bsdf() {
    let mut rng = crate::common::SplitMix64(21);
    let materials: Vec<RandomMaterial> = (0..64).map(|i| RandomMaterial::new(i % 2 == 1, &mut rng)).collect();
    let named: Vec<String> = materials
        .iter()
        .enumerate()
        .map(|(i, m)| format!("\"m{i:03}\": {}", m.ron))
        .collect();
    let s = scene(&format!(
        r#"Scene(
            camera: (position: (0, -4, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 40.0),
            materials: {{{}}},
            shapes: [Sphere(center: (0, 0, 0), radius: 1.0, material: "m000")],
            lights: [Background(radiance: (1, 1, 1))],
        )"#,
        named.join(", ")
    ));
    // 64 pairs per material, fix above the surface for three in four.
    let n = materials.len() * 64;
    let (above, below, generated) = (directions(n, 31, 1.0), directions(n, 32, -1.0), directions(n, 33, 0.0));
    let fix: Vec<[f32; 4]> = (0..n)
        .map(|k| {
            let d = if k % 4 == 3 { below[k] } else { above[k] };
            [d[0], d[1], d[2], (k / 64) as f32]
        })
        .collect();
    let input: Vec<[f32; 4]> = fix.iter().zip(&generated).flat_map(|(a, b)| [*a, *b]).collect();
    let out = probe(&s, PARTS, n as u32, 6, &input, &[]);
    let mut both = [0; 2];
    for (k, o) in out.chunks(6).enumerate() {
        let m = &materials[k / 64];
        let (a, b) = (&fix[k], &generated[k]);
        let what = format!("{} with fix {a:?}, gen {b:?}", m.ron);
        let (whole, diffuse, glossy) = (o[0], o[1], o[2]);
        let [p_diffuse, p_glossy, has_diffuse, has_glossy] = o[3];
        let [d_valid, d_delta, d_continuation, continuation] = o[4];
        let [g_valid, g_delta, g_continuation, valid] = o[5];
        for c in 0..4 {
            // f per channel, then the forward pdf: the parts' pdfs are their lobes' alone, so
            // the whole's is their mixture with the whole's lobe probabilities.
            let (sum, what_sum) = if c < 3 {
                (diffuse[c] as f64 + glossy[c] as f64, "f")
            } else {
                let mix = p_diffuse as f64 * diffuse[3] as f64 + p_glossy as f64 * glossy[3] as f64;
                (mix, "pdf")
            };
            assert!(
                rounding(sum, whole[c] as f64),
                "{what}: the parts' {what_sum} {diffuse:?} and {glossy:?} do not add up to {whole:?}"
            );
        }
        // The diffuse part against the model's diffuse lobe.
        let expected = m.diffuse(a, b);
        let diffuse_expected = if m.pbr {
            a[2] > 0.0 && m.metallic < 1.0 && m.transmission < 1.0
        } else {
            m.diffuse[0] > 0.0
        };
        for c in 0..3 {
            assert!(
                (diffuse[c] as f64 - expected[c]).abs() <= 1e-4 * expected[c] + 1e-7,
                "{what}: the diffuse part is {diffuse:?}, the diffuse lobe {expected:?}"
            );
        }
        let pdf = if diffuse_expected && a[2] > 0.0 && b[2] > 0.0 {
            b[2] as f64 / std::f64::consts::PI
        } else {
            0.0
        };
        assert!(
            (diffuse[3] as f64 - pdf).abs() <= 1e-5 * pdf + 1e-7,
            "{what}: the diffuse part's pdf is {}, cosine sampling's {pdf}",
            diffuse[3]
        );
        let glossy_expected = if m.pbr {
            a[2] > 0.0 || (m.transmission > 0.0 && m.metallic < 1.0)
        } else {
            m.phong || m.specular
        };
        assert!(valid > 0.0, "{what}: the whole BSDF is not valid");
        assert_eq!(
            [has_diffuse, d_valid, d_delta, has_glossy, g_valid],
            [
                diffuse_expected,
                diffuse_expected,
                false,
                glossy_expected,
                glossy_expected
            ]
            .map(|x| x as u8 as f32),
            "{what}: has_diffuse, the diffuse part's valid and is_delta, has_glossy, the glossy part's valid"
        );
        let delta = glossy_expected
            && if m.pbr {
                m.roughness * m.roughness < 1e-3
            } else {
                !m.phong
            };
        assert_eq!(g_delta > 0.0, delta, "{what}: the glossy part's is_delta");
        // Continuation: the diffuse lobe's bound, each part's at most the whole's, and (with
        // fix above, where every lobe is) the whole's at most the parts' together.
        let largest = m.diffuse.iter().copied().fold(0.0, f64::max);
        let d_bound = if diffuse_expected {
            (largest * m.diffuse_share(a)).min(1.0)
        } else {
            0.0
        };
        assert!(
            (d_continuation as f64 - d_bound).abs() <= 1e-5,
            "{what}: the diffuse part continues with {d_continuation}, its bound is {d_bound}"
        );
        assert!(
            d_continuation.max(g_continuation) <= continuation + 1e-6
                && (a[2] < 0.0 || continuation <= d_continuation + g_continuation + 1e-6),
            "{what}: continuation {continuation}, parts {d_continuation} and {g_continuation}"
        );
        let nonzero = |e: [f32; 4]| e[0] + e[1] + e[2] > 0.0;
        both[m.pbr as usize] += (nonzero(diffuse) && nonzero(glossy)) as usize;
    }
    // Both parts nonzero at once in a good share of each model's pairs (about 1 in 14).
    assert!(
        both.iter().all(|&b| b > n / 64),
        "pairs where both parts are nonzero: {both:?}"
    );
}

/// A sphere of `material` under a uniform background of radiance 1, filling most of a
/// 24 x 24 image, rendered with 64 bounces at most.
fn sphere_in_furnace(material: &str, spp: u32, frames: u32) -> ([f64; 3], [f64; 3]) {
    let s = scene(&format!(
        r#"Scene(
            camera: (position: (0, -4, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 40.0),
            materials: {{"m": {material}}},
            shapes: [Sphere(center: (0, 0, 0), radius: 1.2, material: "m")],
            lights: [Background(radiance: (1, 1, 1))],
            integrator: (max_path_length: 64, russian_roulette: Albedo, mis: Balance),
        )"#
    ));
    let r = render(&s, "pt", "NaivePTsk", (24, 24), spp, frames, 5, &[]);
    crate::common::assert_finite(&r.image, material);
    let (mean, se, _) = region(&r.image, |x, y| {
        let (dx, dy) = (x as f64 - 11.5, y as f64 - 11.5);
        dx * dx + dy * dy < 64.0
    });
    eprintln!("{material}: {mean:?} +- {se:?}");
    (mean, se)
}

#[test]
fn pbr_spheres_under_uniform_background() {
    // A lossless smooth dielectric sphere in a uniform environment: every path leaves with
    // the background's radiance whatever it does inside, each path's weight is exactly 1
    // (no noise), so the pixels are 1 up to rounding and paths cut at 64 bounces.
    // So is a thin-walled one.
    for m in [
        "(pbr: (roughness: 0.0, transmission: 1.0))",
        "(pbr: (roughness: 0.0, transmission: 1.0, thin_walled: true))",
    ] {
        let (mean, _) = sphere_in_furnace(m, 1, 1);
        assert!(mean.iter().all(|c| (c - 1.0).abs() < 1e-3), "{m}: {mean:?}");
    }
    // Rough white glass and metal lose the light of multiple scattering between microfacets
    // but never gain any: at most 1 within 4 standard errors, and not far below (white
    // furnace bounds above).
    for m in [
        "(pbr: (roughness: 0.4, transmission: 1.0))",
        "(pbr: (roughness: 0.4, transmission: 1.0, thin_walled: true))",
        "(pbr: (metallic: 1.0, roughness: 0.5))",
    ] {
        let (mean, se) = sphere_in_furnace(m, 4, 4);
        for c in 0..3 {
            assert!(mean[c] <= 1.0 + 4.0 * se[c] && mean[c] > 0.8, "{m}: {mean:?} +- {se:?}");
        }
    }
}

/// A 32 x 32 image of a unit square light (radiance 1, black around it) 9 units in front of
/// the camera, seen through a 4 x 4 pane of `pane` (a material, or none) turned 45 degrees
/// about the vertical, halfway: the pane's reflection sees only the black surroundings.
fn light_behind_pane(pane: Option<&str>) -> lightgraph::run::Image {
    let (material, shape) = match pane {
        Some(m) => (
            format!(r#""pane": {m},"#),
            r#"Quad(corners: ((-2, -2, 2), (2, -2, -2), (2, 2, -2), (-2, 2, 2)), material: "pane"),"#,
        ),
        None => (String::new(), ""),
    };
    let s = scene(&format!(
        r#"Scene(
            camera: (position: (0, 0, 6), look: Target((0, 0, 0)), up: (0, 1, 0), fov_degrees: 30.0),
            materials: {{{material} "black": (diffuse: (0, 0, 0))}},
            shapes: [
                {shape}
                Quad(corners: ((-0.5, -0.5, -3), (0.5, -0.5, -3), (0.5, 0.5, -3), (-0.5, 0.5, -3)),
                     material: "black", emission: Some((1, 1, 1))),
            ],
            integrator: (max_path_length: 4, russian_roulette: Albedo, mis: Balance),
        )"#
    ));
    let r = render(&s, "pt", "NaivePTsk", (32, 32), 16, 16, 3, &[]);
    crate::common::assert_finite(&r.image, pane.unwrap_or("no pane"));
    r.image
}

/// The image's centroid along x (red channel), with its standard error: sum x v / sum v,
/// whose variance is sum (x - c)^2 var(v) / (sum v)^2 to first order, pixels independent.
fn centroid_x(image: &lightgraph::run::Image) -> (f64, f64) {
    let pixel = |i: usize| {
        let x = (i % image.width as usize) as f64 + 0.5;
        (
            x,
            image.mean[i][0] as f64,
            image.variance[i][0] as f64 / image.frames as f64,
        )
    };
    let (mut moment, mut total) = (0.0, 0.0);
    for i in 0..image.mean.len() {
        let (x, v, _) = pixel(i);
        moment += x * v;
        total += v;
    }
    let c = moment / total;
    let var: f64 = (0..image.mean.len())
        .map(|i| {
            let (x, _, var) = pixel(i);
            (x - c) * (x - c) * var
        })
        .sum();
    (c, var.sqrt() / total)
}

#[test]
fn a_thin_walled_pane_neither_moves_nor_dims_a_light_beyond_its_slab_reflectance() {
    // Through a smooth thin pane of index 1.5 at 45 degrees the light's image stays where it
    // is and keeps T = 1 - R' of its radiance, R' = 2R / (1 + R) = 0.0957 the slab's
    // reflectance (a single interface's R = 0.0503 would keep 0.950, 9 standard errors away).
    // Each camera path through the pane is a Bernoulli trial (radiance 1 with probability T,
    // else 0), so the ratio of the image sums is T within 4 standard errors (0.005, from the
    // frames' variances: 256 samples over the light's 44 pixels, and the bare image's edge
    // pixels), and the centroids agree within 4 standard errors (about 0.015 pixel) plus 0.05
    // pixel. A solid pane of the same glass refracts the rays by 17 degrees: its image moves
    // by about 5 pixels, which the same comparison must catch.
    let bare = light_behind_pane(None);
    let thin = light_behind_pane(Some(&thin_glass(0.0)));
    let solid = light_behind_pane(Some("(pbr: (roughness: 0.0, transmission: 1.0, ior: 1.5))"));
    let all = |_: u32, _: u32| true;
    let ((b, b_se, _), (t, t_se, _)) = (region(&bare, all), region(&thin, all));
    let ratio = t[0] / b[0];
    let ratio_se = ratio * ((t_se[0] / t[0]).powi(2) + (b_se[0] / b[0]).powi(2)).sqrt();
    let r = fresnel(std::f64::consts::FRAC_1_SQRT_2, 1.5);
    let expected = 1.0 - 2.0 * r / (1.0 + r);
    eprintln!("thin pane: transmittance {ratio} +- {ratio_se}, slab {expected}");
    assert!(
        (ratio - expected).abs() <= 4.0 * ratio_se,
        "the thin pane keeps {ratio} +- {ratio_se} of the light, the slab {expected}"
    );
    let (c_bare, se_bare) = centroid_x(&bare);
    let (c_thin, se_thin) = centroid_x(&thin);
    let (c_solid, se_solid) = centroid_x(&solid);
    eprintln!("centroids: bare {c_bare} +- {se_bare}, thin {c_thin} +- {se_thin}, solid {c_solid} +- {se_solid}");
    let shift = |c: f64, se: f64| (c - c_bare).abs() - 4.0 * (se * se + se_bare * se_bare).sqrt();
    assert!(
        shift(c_thin, se_thin) <= 0.05,
        "the thin pane moves the light's image from x = {c_bare} to {c_thin}"
    );
    assert!(
        shift(c_solid, se_solid) > 2.0,
        "a solid pane should move the light's image, from x = {c_bare}; it is at {c_solid}"
    );
}
