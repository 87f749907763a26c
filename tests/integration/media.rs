//! Participating media in the path tracer (docs/media.md), against closed forms: the
//! transmittance through an absorbing sphere, single scattering in a half-space under a
//! distant light (isotropic and Henyey-Greenstein), and furnaces in media that absorb nothing
//! (isotropic and forward scattering). Each compares a region's mean with the exact value
//! within 3 standard errors, as tests/integration/analytic.rs does, with the same demand on
//! the standard error (under 1.5% of the value). Also: every layout renders a media scene alike
//! to float rounding, graphs that do not handle media refuse such a scene, and kernels for a
//! scene without media hold no media code or buffer.

use crate::common::{assert_analytic, assert_same_render, data, kernel_sources, region, render};
use lightgraph::run::{LoadedScene, RunSpec, load_graph, load_scene};

fn scene(name: &str) -> LoadedScene {
    load_scene(data(&format!("scenes/{name}.ron")).to_str().unwrap()).unwrap()
}

/// The background's radiance in the test scenes.
const BACKGROUND: [f64; 3] = [1.0, 2.0, 4.0];

/// The exact mean radiance of pixel (x, y) of the absorbing sphere's image (`size` pixels):
/// the background times the transmittance exp(-sigma_a chord) along each ray, averaged over
/// the pixel's footprint on a 16 x 16 grid (the render jitters its rays uniformly over it).
fn absorbed(x: u32, y: u32, (w, h): (u32, u32), sigma: [f64; 3]) -> [f64; 3] {
    // Camera at (0, -4, 0) looking at the origin, 40 degrees across the width; unit sphere.
    let t = 20f64.to_radians().tan();
    let n = 16;
    let mut sum = [0f64; 3];
    for j in 0..n {
        for i in 0..n {
            let px = x as f64 + (i as f64 + 0.5) / n as f64;
            let py = y as f64 + (j as f64 + 0.5) / n as f64;
            let d = [
                (2.0 * px / w as f64 - 1.0) * t,
                1.0,
                (1.0 - 2.0 * py / h as f64) * t * h as f64 / w as f64,
            ];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            // Distance of the ray's line from the centre: |o|^2 - (o.d)^2 with o = (0, -4, 0).
            let od = -4.0 * d[1] / len;
            let r2 = 16.0 - od * od;
            let chord = if r2 < 1.0 { 2.0 * (1.0 - r2).sqrt() } else { 0.0 };
            for c in 0..3 {
                sum[c] += BACKGROUND[c] * (-sigma[c] * chord).exp();
            }
        }
    }
    sum.map(|s| s / (n * n) as f64)
}

#[test]
fn an_absorbing_sphere_transmits_the_background_by_beer_lambert() {
    let size = (32, 32);
    let r = render(&scene("media-absorbing-sphere"), "pt", "NaivePTsk", size, 4, 32, 3, &[]);
    // The pixels whose rays cross the sphere for most of their footprint: the centre 12 x 12.
    let inside = |x: u32, y: u32| (10..22).contains(&x) && (10..22).contains(&y);
    let (mean, se, n) = region(&r.image, inside);
    let mut expected = [0f64; 3];
    for y in 10..22 {
        for x in 10..22 {
            let e = absorbed(x, y, size, [0.4, 0.8, 1.6]);
            for c in 0..3 {
                expected[c] += e[c] / n as f64;
            }
        }
    }
    assert_analytic("absorbing sphere", mean, se, expected, 3.0, 0.0);
}

/// Henyey-Greenstein's phase function at the cosine `cos` between the direction light travels
/// before and after scattering (forward scattering for g > 0).
fn henyey_greenstein(g: f64, cos: f64) -> f64 {
    (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5))
}

#[test]
fn single_scattering_in_a_half_space_matches_its_closed_form() {
    // A vertical camera ray into a half-space of albedo a under a distant light of irradiance
    // E travelling at angle theta_l from the vertical: scattered once at depth z, the light
    // comes in through z / mu_l of medium, so L = a p E sigma_t int exp(-sigma_t z (1 + 1 /
    // mu_l)) dz = a p E mu_l / (mu_l + 1), whatever sigma_t. Here mu_l = 0.5 and light turns
    // from (sin 60, 0, -cos 60) to (0, 0, 1): cos = -0.5. The 1-degree pinhole makes every ray
    // vertical to 0.01% of this value.
    let albedo = [0.5, 0.8, 1.0];
    let irradiance = [1.0, 2.0, 4.0];
    for (name, g) in [("media-half-space-isotropic", 0.0), ("media-half-space-hg", 0.5)] {
        let r = render(&scene(name), "pt", "NaivePTsk", (16, 16), 4, 64, 11, &[]);
        let (mean, se, _) = region(&r.image, |_, _| true);
        let p = henyey_greenstein(g, -0.5);
        let expected = [0, 1, 2].map(|c| albedo[c] * p * irradiance[c] * 0.5 / 1.5);
        assert_analytic(name, mean, se, expected, 3.0, 0.0);
    }
}

#[test]
fn furnaces_in_media_that_absorb_nothing_show_the_background() {
    for name in ["media-furnace-isotropic", "media-furnace-hg"] {
        let r = render(&scene(name), "pt", "NaivePTsk", (16, 16), 4, 64, 5, &[]);
        assert_eq!(r.loops_capped, 0, "{name}");
        let (mean, se, _) = region(&r.image, |_, _| true);
        assert_analytic(name, mean, se, BACKGROUND, 3.0, 0.0);
    }
}

#[test]
fn every_path_tracing_layout_renders_a_media_scene_alike() {
    let s = load_scene("media-sphere").unwrap();
    let base = render(&s, "pt", "NaivePTsk", (16, 16), 1, 2, 9, &[]);
    for layout in ["NaivePTmk", "RegenerationPTmk2", "StreamingPTmk3", "WavefrontPT"] {
        let other = render(&s, "pt", layout, (16, 16), 1, 2, 9, &[]);
        assert_same_render(&base, &other, &format!("media-sphere: NaivePTsk and {layout}"));
    }
}

#[test]
fn graphs_that_do_not_handle_media_refuse_a_scene_with_them() {
    let s = load_scene("media-fog").unwrap();
    for graph in ["bpt-lvc", "vcm", "lt"] {
        let g = load_graph(graph).unwrap();
        let spec = RunSpec {
            scene: "media-fog".into(),
            ..RunSpec::default()
        };
        let e = spec.options(&s, &g).expect_err("refused").to_string();
        assert!(
            e.contains(&format!("graph '{graph}' does not handle participating media"))
                && e.contains("render it with pt"),
            "{e}"
        );
    }
    let pt = load_graph("pt").unwrap();
    RunSpec::default().options(&s, &pt).expect("pt handles media");
}

#[test]
fn kernels_for_a_scene_without_media_hold_no_media_code_or_buffer() {
    let plain = load_scene("cornell-diffuse").unwrap();
    let fog = load_scene("media-fog").unwrap();
    for layout in ["NaivePTsk", "WavefrontPT"] {
        let with = kernel_sources("pt", layout, &fog, &[], false);
        let without = kernel_sources("pt", layout, &plain, &[], false);
        for word in [
            "material_media",
            "media_info",
            "fn medium_free_flight",
            "fn media_shadow_transmittance",
        ] {
            assert!(with.contains(word), "{layout}: the media scene's kernels lack {word}");
            assert!(
                !without.contains(word),
                "{layout}: cornell-diffuse's kernels hold {word}"
            );
        }
    }
}
