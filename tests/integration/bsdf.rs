//! The BSDFs on the GPU (`shaders/lib/bsdf.wgsl`), through the probe harness: sampled
//! directions against the pdfs (chi-square), the pdfs' integrals and lost samples, albedo
//! (white furnace), reciprocity, forward/reverse pdf consistency; and a PBR scene that must
//! render its exact radiance.
//!
//! The BSDF sits on a surface with normal +z (the local frame is the world frame); `fix` is
//! the direction towards the previous vertex.

use crate::chi2::{SphereBins, goodness_of_fit, significance};
use crate::common::{region, render};
use crate::probe::{probe, scene};
use lightgraph::render::LoadedScene;
use lightgraph_engine::ConstValue;

/// The chi-square tests in this file, for the Šidák-corrected significance of each.
const CHI2_TESTS: u32 = 16;
/// Samples per chi-square test: with 24 × 48 bins, a smooth lobe expects about 200 per bin.
/// Bins where a pdf's support ends (rough refraction's) need the fine sub-grid: at 4 × 4
/// points the midpoint rule misses enough of their mass to fail the test.
const SAMPLES: u32 = 200_000;
/// Quadrature sub-grid per bin (the integral's error is estimated from half of it), on the
/// sphere and in the caps around narrow lobes.
const SUB: usize = 8;
const SUB_CAP: usize = 8;

const SETUP: &str = "
fn probe_bsdf(towards_previous: vec3<f32>, adjoint: bool) -> Bsdf {
    var b = bsdf_setup(material_at(0u, vec2<f32>(0.0)), vec3<f32>(0.0, 0.0, 1.0), normalize(towards_previous));
    b.adjoint = adjoint;
    return b;
}
";

/// Per index: the sampled direction with its kind in w (0 none, 1 continuous, 2 delta
/// reflection, 3 delta refraction, -1 continuous where the pdf is 0), and the weight
/// f cos / pdf.
const SAMPLE: &str = "
fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let b = probe_bsdf(vec3<f32>(FIX_X, FIX_Y, FIX_Z), ADJOINT);
    var rng = rng_seed(frame.seed, frame.index, index);
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
/// (continuation, is_delta).
const EVAL: &str = "
fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let b = probe_bsdf(vec3<f32>(FIX_X, FIX_Y, FIX_Z), ADJOINT);
    if (index == N - 1u) {
        out[index * PER_INDEX] = vec4<f32>(b.diffuse_prob, b.spec_prob, b.reflect_prob, b.refract_prob);
        out[index * PER_INDEX + 1u] = vec4<f32>(b.continuation, select(0.0, 1.0, b.is_delta), 0.0, 0.0);
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

/// A scene whose material 0 is `material` (RON).
fn material_scene(material: &str) -> LoadedScene {
    scene(&format!(
        r#"Scene(
            camera: (position: (0, -4, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 40.0),
            materials: {{"m": {material}}},
            shapes: [Sphere(center: (0, 0, 0), radius: 1.0, material: "m")],
            lights: [Background(radiance: (1, 1, 1))],
        )"#
    ))
}

fn constants(fix: [f32; 3], adjoint: bool) -> Vec<(&'static str, ConstValue)> {
    vec![
        ("FIX_X", ConstValue::F32(fix[0])),
        ("FIX_Y", ConstValue::F32(fix[1])),
        ("FIX_Z", ConstValue::F32(fix[2])),
        ("ADJOINT", ConstValue::Bool(adjoint)),
    ]
}

/// What one BSDF set-up gives: samples, their weights, and the set-up's lobe probabilities.
struct Sampled {
    samples: Vec<[f32; 4]>,
    weights: Vec<[f32; 3]>,
    /// Diffuse, rough specular, delta reflection, delta refraction.
    lobes: [f32; 4],
    continuation: f32,
}

fn sample(s: &LoadedScene, fix: [f32; 3], adjoint: bool, n: u32) -> Sampled {
    let c = constants(fix, adjoint);
    let out = probe(s, &format!("{SETUP}{SAMPLE}"), n, 2, &[], &c);
    let setup = probe(s, &format!("{SETUP}{EVAL}"), 1, 2, &[], &c);
    Sampled {
        samples: out.iter().step_by(2).copied().collect(),
        weights: out.iter().skip(1).step_by(2).map(|w| [w[0], w[1], w[2]]).collect(),
        lobes: setup[0],
        continuation: setup[1][0],
    }
}

/// f and the forward pdf at each of `directions`.
fn eval(s: &LoadedScene, fix: [f32; 3], adjoint: bool, directions: &[[f32; 4]]) -> Vec<([f32; 3], f32)> {
    let n = directions.len() as u32 + 1;
    let out = probe(s, &format!("{SETUP}{EVAL}"), n, 2, directions, &constants(fix, adjoint));
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
    let s = material_scene(material);
    let sampled = sample(&s, fix, false, SAMPLES);
    let unsupported = sampled.samples.iter().filter(|s| s[3] < 0.0).count();
    assert_eq!(unsupported, 0, "{what}: samples where the pdf is 0");
    let sub = if grid.is_sphere() { SUB } else { SUB_CAP };
    let fine = grid.quadrature_points(sub);
    let coarse = grid.quadrature_points(sub / 2);
    let all: Vec<[f32; 4]> = fine.iter().chain(&coarse).copied().collect();
    let pdf: Vec<f32> = eval(&s, fix, false, &all).iter().map(|e| e.1).collect();
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

#[test]
fn chi2_pbr_mixture() {
    // Every lobe at once: metal, dielectric reflection, diffuse and transmission.
    let m = "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5))";
    chi2_case("mixture outside", m, OBLIQUE, sphere());
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

#[test]
fn white_furnace() {
    // White metals reflect at most 1. Single-scattering GGX loses the light that would
    // scatter again between microfacets, and with it the reflections its long-tailed normal
    // distribution sends below the horizon: next to nothing at roughness 0.05; at alpha 1,
    // half the visible normals at normal incidence are tilted beyond 45 degrees, and the loss
    // reaches 60-70% (Heitz et al. 2016 show the same for their single-scattering baseline).
    // The lower bounds are those losses with a margin: they catch a lobe that loses more.
    // A white dielectric with transmission conserves energy (adjoint form: integrated over
    // the directions light leaves in) up to the same loss; a smooth one exactly. The diffuse
    // base of plastic loses 1 - F_avg (9% at ior 1.5). The continuation probability is at
    // least the albedo.
    let normal = [0.0, 0.0, 1.0];
    let grazing = [0.94, 0.0, 0.342]; // 70 degrees
    let cases: &[(&str, [f32; 3], f64)] = &[
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
        ("(pbr: (roughness: 0.5))", OBLIQUE, 0.85),
    ];
    for &(material, fix, lower) in cases {
        let s = material_scene(material);
        let sampled = sample(&s, fix, true, 100_000);
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

/// Random unit directions (SplitMix64), each with z of the sign `side` gives (0 any).
fn directions(n: usize, seed: u64, side: f32) -> Vec<[f32; 4]> {
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

/// Reciprocity and pdf consistency on random pairs of directions: `a` from `side_a`, `b`
/// from `side_b`.
fn check_pairs(material: &str, side_a: f32, side_b: f32, ior: f32) {
    let s = material_scene(material);
    let a = directions(2000, 11, side_a);
    let b = directions(2000, 12, side_b);
    let input: Vec<[f32; 4]> = a.iter().zip(&b).flat_map(|(x, y)| [*x, *y]).collect();
    let out = probe(&s, &format!("{SETUP}{PAIRS}"), a.len() as u32, 4, &input, &[]);
    let mut nonzero = 0;
    for (k, o) in out.chunks(4).enumerate() {
        let (ab, ba, rev, ba_adj) = (o[0], o[1], o[2], o[3]);
        let eta = |d: &[f32; 4]| if d[2] > 0.0 { 1.0 } else { ior };
        let (ea, eb) = (eta(&a[k]), eta(&b[k]));
        for c in 0..3 {
            // Radiance BSDFs satisfy f(a, b) / eta_a^2 = f(b, a) / eta_b^2 (fix = a: eta_a is
            // the index on the side the radiance leaves to); the adjoint swaps the arguments.
            assert!(
                close(ab[c] / (ea * ea), ba[c] / (eb * eb)),
                "{material}: f({:?}, {:?}) = {} but f back = {}",
                a[k],
                b[k],
                ab[c],
                ba[c]
            );
            assert!(
                close(ab[c], ba_adj[c]),
                "{material}: f({:?}, {:?}) = {} but the adjoint f back = {}",
                a[k],
                b[k],
                ab[c],
                ba_adj[c]
            );
        }
        assert!(
            close(rev[0], ba[3]) && close(rev[1], ab[3]),
            "{material}: pdfs ({:?}, {:?}): forward {} reverse {}, back: forward {} reverse {}",
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
    assert!(nonzero > 300, "{material}: only {nonzero} pairs with a nonzero pdf");
}

#[test]
fn reflection_is_reciprocal_and_pdfs_are_consistent() {
    for m in [
        "(pbr: (base_color: (0.9, 0.6, 0.3), metallic: 1.0, roughness: 0.3))",
        "(pbr: (base_color: (0.2, 0.5, 0.8), roughness: 0.5))",
        "(pbr: (base_color: (0.7, 0.8, 0.9), metallic: 0.3, roughness: 0.5, transmission: 0.5))",
        "(diffuse: (0.2, 0.3, 0.4), phong: (0.5, 0.5, 0.5), phong_exponent: 20.0)",
    ] {
        check_pairs(m, 1.0, 1.0, 1.5);
    }
    let glass = "(pbr: (base_color: (1, 1, 1), metallic: 0.2, roughness: 0.4, transmission: 0.8, ior: 1.5))";
    check_pairs(glass, -1.0, -1.0, 1.5);
}

#[test]
fn refraction_is_reciprocal_up_to_eta_squared_and_pdfs_are_consistent() {
    let glass = "(pbr: (base_color: (0.9, 0.8, 1.0), metallic: 0.2, roughness: 0.4, transmission: 0.8, ior: 1.5))";
    check_pairs(glass, 1.0, -1.0, 1.5);
    check_pairs(glass, -1.0, 1.0, 1.5);
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
    let (mean, _) = sphere_in_furnace("(pbr: (roughness: 0.0, transmission: 1.0))", 1, 1);
    assert!(mean.iter().all(|c| (c - 1.0).abs() < 1e-3), "smooth glass: {mean:?}");
    // Rough white glass and metal lose the light of multiple scattering between microfacets
    // but never gain any: at most 1 within 4 standard errors, and not far below (white
    // furnace bounds above).
    for m in [
        "(pbr: (roughness: 0.4, transmission: 1.0))",
        "(pbr: (metallic: 1.0, roughness: 0.5))",
    ] {
        let (mean, se) = sphere_in_furnace(m, 4, 4);
        for c in 0..3 {
            assert!(mean[c] <= 1.0 + 4.0 * se[c] && mean[c] > 0.8, "{m}: {mean:?} +- {se:?}");
        }
    }
}
