//! Analytic checks: scenes whose radiance is known in closed form. Each check compares the
//! mean over a region with the exact value within 3 standard errors, the standard error
//! computed from the render's own per-frame estimates (independent frames, independent
//! pixels); and it requires that standard error to be small (under 1.5% of the value), so
//! the check has the power to catch a bias of a few percent.

use crate::common::{assert_analytic, data, region, render};
use lightgraph::run::load_scene;

/// The module's check: within 3 standard errors (see the module comment).
fn check(what: &str, mean: [f64; 3], se: [f64; 3], expected: [f64; 3]) {
    assert_analytic(what, mean, se, expected, 3.0, 0.0);
}

/// The pixels whose whole footprint shows the sphere: all four corner rays hit it.
fn sphere_interior(width: u32, height: u32) -> impl Fn(u32, u32) -> bool {
    // Camera at (0, -4, 0) looking at the origin, 40 degree horizontal fov, unit sphere.
    let t = (20f64).to_radians().tan();
    move |x, y| {
        [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
            let nx = 2.0 * (x + dx) as f64 / width as f64 - 1.0;
            let ny = 1.0 - 2.0 * (y + dy) as f64 / height as f64;
            let d = [nx * t, 1.0, ny * t * height as f64 / width as f64];
            let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            // Distance from the origin to the ray line, squared: |o|^2 - (o.d)^2 / |d|^2.
            let od = -4.0 * d[1];
            16.0 - od * od / len2 < 0.95 * 0.95
        })
    }
}

#[test]
fn diffuse_sphere_under_uniform_background_is_albedo_times_background() {
    let scene = load_scene(data("scenes/diffuse-sphere-background.ron").to_str().unwrap()).unwrap();
    let (w, h) = (48, 48);
    for layout in ["NaivePTsk", "NaivePTmk"] {
        let r = render(&scene, "pt", layout, (w, h), 4, 24, 3, &[]);
        let (mean, se, n) = region(&r.image, sphere_interior(w, h));
        assert!(n > 500, "{n} interior pixels");
        check(&format!("sphere ({layout})"), mean, se, [0.6, 0.8, 0.8]);
    }
}

#[test]
fn closed_emissive_box_converges_to_le_over_one_minus_albedo() {
    for (albedo, frames) in [(0.5, 16), (0.95, 64)] {
        let scene = load_scene(data(&format!("scenes/emissive-box-{albedo}.ron")).to_str().unwrap()).unwrap();
        let r = render(&scene, "pt", "NaivePTsk", (32, 32), 4, frames, 11, &[]);
        assert_eq!(r.loops_capped, 0);
        let (mean, se, _) = region(&r.image, |_, _| true);
        let expected = [0.5, 1.0, 2.0].map(|le| le / (1.0 - albedo));
        check(&format!("emissive box, albedo {albedo}"), mean, se, expected);
    }
}
