//! Participating media in the path tracer (docs/media.md), against closed forms: the
//! transmittance through an absorbing sphere, single scattering in a half-space under a
//! distant light (isotropic and Henyey-Greenstein), and furnaces in media that absorb nothing
//! (isotropic and forward scattering). Each compares a region's mean with the exact value
//! within 3 standard errors, as tests/integration/analytic.rs does, with the same demand on
//! the standard error (under 1.5% of the value). Also: light tracing agrees with path tracing
//! in media (as tests/integration/bpt.rs compares them), every layout of each renders a media
//! scene alike to float rounding, graphs that do not handle media refuse such a scene, and
//! kernels for a scene without media hold no media code or buffer.

use crate::bpt::direct_light_blocks;
use crate::common::{assert_analytic, assert_same_render, data, kernel_sources, region, render, render_with_layout};
use crate::frames::{render_frames, worst_z};
use lightgraph::run::{LayoutOverrides, LoadedScene, RunSpec, load_graph, load_scene};

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

/// Asserts that NaivePTsk, NaivePTmk, RegenerationPTmk2, StreamingPTmk3 and WavefrontPT render
/// `scene` (called `what`) alike to float rounding.
pub fn assert_path_tracing_layouts_alike(scene: &LoadedScene, what: &str) {
    let base = render(scene, "pt", "NaivePTsk", (16, 16), 1, 2, 9, &[]);
    for layout in ["NaivePTmk", "RegenerationPTmk2", "StreamingPTmk3", "WavefrontPT"] {
        let other = render(scene, "pt", layout, (16, 16), 1, 2, 9, &[]);
        assert_same_render(&base, &other, &format!("{what}: NaivePTsk and {layout}"));
    }
}

#[test]
fn every_path_tracing_layout_renders_a_media_scene_alike() {
    assert_path_tracing_layouts_alike(&load_scene("media-sphere").unwrap(), "media-sphere");
}

/// Light tracing against path tracing on `media-lights`: light sub-paths start in two media,
/// neither the camera's (an area light in a box of fog, another inside a null sphere of
/// coloured absorbing juice in the fog), scatter in the fog by Henyey-Greenstein, light the
/// floor and cross the null boundaries on their way to the camera, medium vertices connected
/// to it as surface ones are. The per-block means of 48 independent frames agree within 4
/// combined standard errors (the statistics of light tracing against path tracing in
/// tests/integration/bpt.rs: |t| > 4 about once in 4000 per block and channel), outside any
/// block where the camera sees a light (La E, which light tracing cannot sample; none here).
/// 16 samples a pixel a frame keep every block's standard error under 5% of its mean. The
/// test sees a wrong start medium: sub-paths started in the camera's (vacuum) instead of their
/// light's differ by up to 172 standard errors.
#[test]
fn light_tracing_agrees_with_path_tracing_in_media() {
    let s = scene("media-lights");
    let (size, n) = (32, 4);
    let pt = render_frames(&s, "pt", "NaivePTsk", size, 16, 48, 61, n);
    let lt = render_frames(&s, "lt", "LTsk", size, 16, 48, 62, n);
    let keep: Vec<bool> = direct_light_blocks(&s, size, n).iter().map(|d| !d).collect();
    assert!(
        keep.iter().filter(|k| **k).count() >= 12,
        "too few blocks left: {keep:?}"
    );
    let z = worst_z(
        &lt,
        &pt,
        &keep,
        &vec![false; keep.len()],
        0.05,
        "media-lights: lt vs pt",
    );
    assert!(
        z < 4.0,
        "light tracing differs from path tracing in media by {z:.2} standard errors"
    );
}

#[test]
fn every_light_tracing_layout_renders_a_media_scene_alike() {
    let s = scene("media-lights");
    let base = render(&s, "lt", "LTsk", (16, 16), 1, 2, 9, &[]);
    for layout in ["LTmk", "StreamingLTmk"] {
        let other = render(&s, "lt", layout, (16, 16), 1, 2, 9, &[]);
        assert_same_render(&base, &other, &format!("media-lights: LTsk and {layout}"));
    }
}

/// A sky behind a fog that fills all space lights nothing (its light crosses an infinite
/// distance of fog): path tracing renders black, and light tracing, whose sub-paths from the
/// sky would start in the fog at the scene's bounding sphere, too. Without the fog the floor is
/// lit, in both.
#[test]
fn a_sky_behind_an_unbounded_fog_lights_nothing() {
    let path = data("scenes/media-unbounded-fog.ron");
    let clear = std::env::temp_dir().join(format!("lightgraph-clear-sky-{}.ron", std::process::id()));
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(
        &clear,
        text.replace("camera_medium: Some(\"fog\")", "camera_medium: None"),
    )
    .unwrap();
    let (fog, sky) = (
        scene("media-unbounded-fog"),
        load_scene(clear.to_str().unwrap()).unwrap(),
    );
    std::fs::remove_file(&clear).unwrap();
    for (graph, layout) in [("pt", "NaivePTsk"), ("lt", "LTsk")] {
        let dark = render(&fog, graph, layout, (8, 8), 1, 4, 3, &[]);
        assert!(
            dark.image.mean.iter().all(|p| *p == [0.0; 3]),
            "{graph}: light through the fog"
        );
        let lit = render(&sky, graph, layout, (8, 8), 1, 4, 3, &[]);
        let (mean, _, _) = region(&lit.image, |_, _| true);
        assert!(mean[0] > 0.1, "{graph}: the floor under a clear sky is dark ({mean:?})");
    }
}

/// Light tracing with every feature compiled in (media among them) renders a scene without
/// media as its specialised kernels do, tracing the same rays: no medium is looked up for a
/// light where the scene has none.
#[test]
fn light_tracing_with_media_compiled_in_renders_a_scene_without_them_alike() {
    let s = load_scene("cornell-diffuse").unwrap();
    let plain = render(&s, "lt", "LTsk", (16, 16), 1, 2, 5, &[]);
    let all = LayoutOverrides {
        all_features: true,
        ..Default::default()
    };
    let general = render_with_layout(&s, "lt", "LTsk", (16, 16), 1, 2, 5, &[], all);
    assert_same_render(&plain, &general, "cornell-diffuse: lt with every feature");
}

#[test]
fn graphs_that_do_not_handle_media_refuse_a_scene_with_them() {
    let s = load_scene("media-fog").unwrap();
    for graph in ["bpt-lvc", "vcm"] {
        let g = load_graph(graph).unwrap();
        let spec = RunSpec {
            scene: "media-fog".into(),
            ..RunSpec::default()
        };
        let e = spec.options(&s, &g).expect_err("refused").to_string();
        let able = e.split("render it with ").nth(1).unwrap_or("");
        assert!(
            e.contains(&format!("graph '{graph}' does not handle participating media")) && able.starts_with("lt, pt "),
            "{e}"
        );
    }
    for graph in ["pt", "lt"] {
        let g = load_graph(graph).unwrap();
        RunSpec::default().options(&s, &g).expect("handles media");
    }
}

#[test]
fn kernels_for_a_scene_without_media_hold_no_media_code_or_buffer() {
    let plain = load_scene("cornell-diffuse").unwrap();
    let fog = load_scene("media-fog").unwrap();
    for (graph, layout) in [
        ("pt", "NaivePTsk"),
        ("pt", "WavefrontPT"),
        ("lt", "LTsk"),
        ("lt", "StreamingLTmk"),
    ] {
        let with = kernel_sources(graph, layout, &fog, &[], false);
        let without = kernel_sources(graph, layout, &plain, &[], false);
        for word in [
            "material_media",
            "media_info",
            "fn medium_free_flight",
            "fn flight_through_media",
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
