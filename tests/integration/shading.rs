//! Shading normals: triangles with vertex normals are shaded with the interpolated normal in
//! every estimator. Two analytic checks: a square whose vertex normals are tilted 30 degrees
//! from its face has the radiance of a plane of the tilted normal (in every estimator: the
//! ones tracing from the lights need the adjoint BSDF's correction, the merging ones the
//! density estimation's), and a sphere made of triangles with the sphere's normals at its
//! vertices renders as the analytic sphere does.

use crate::common::{assert_analytic, data, region, render};
use lightgraph::run::{Image, LoadedScene, load_scene};
use lightgraph_engine::ConstValue;
use lightgraph_scenes::bvh::BvhKind;

/// The estimators of the tilted square, each in one layout, with the samples that bring the
/// standard error of the region mean under 1.5% on lavapipe (LT and the merging ones need more
/// than PT, whose only noise is the pixel jitter).
const ESTIMATORS: &[(&str, &str, u32)] = &[
    ("pt", "NaivePTsk", 4),
    ("lt", "LTsk", 16),
    ("bpt-lvc", "LVC-BPTsk", 8),
    ("vcm", "VCMsk", 8),
    ("ppm", "PPMsk", 16),
    ("sppm", "SPPMsk", 16),
    ("pbpm", "PBPMsk", 16),
];

/// The pixels of a `size` x `size` image of the tilted-normals scene whose footprint lies on
/// the square, `margin` (in scene units) inside its edges: camera at (0, -4, 0) looking at the
/// origin with a 40 degree field of view, the square [-1, 1]^2 at y = 0.
pub(crate) fn on_square(size: u32, margin: f64) -> impl Fn(u32, u32) -> bool {
    let half = 4.0 * (20f64).to_radians().tan();
    move |x, y| {
        [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
            let u = (2.0 * (x + dx) as f64 / size as f64 - 1.0) * half;
            let v = (1.0 - 2.0 * (y + dy) as f64 / size as f64) * half;
            u.abs() < 1.0 - margin && v.abs() < 1.0 - margin
        })
    }
}

#[test]
fn a_square_with_tilted_vertex_normals_is_shaded_by_them_in_every_estimator() {
    let scene = load_scene(data("scenes/tilted-normals-quad.ron").to_str().unwrap()).unwrap();
    check_tilted_square(&scene, "pinhole", tilted_radiance());
}

/// The radiance of the tilted square's scene: albedo / pi * E * (l . ns), see the scene file.
fn tilted_radiance() -> [f64; 3] {
    let cosine = (30f64.to_radians().cos() - 30f64.to_radians().sin()) / 2f64.sqrt();
    [1.0, 2.0, 0.5].map(|e| 0.8 * cosine * e)
}

#[test]
fn through_a_thin_lens_every_estimator_sees_the_tilted_square_alike() {
    // The same square through a lens of radius 0.05 focused at 2 (the square, at 4, is out of
    // focus: a point of it spreads over about 0.05 of its width, inside the region's margin).
    // Its radiance is the same from every point of the lens, so every estimator must still
    // find it: the light tracers' connections to the lens (the lens point's density against
    // its importance) as much as the camera's rays.
    let path = data("scenes/tilted-normals-quad.ron");
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "fov_degrees: 40.0)",
        "fov_degrees: 40.0, lens: Some((aperture_radius: 0.05, focus_distance: 2.0)))",
    );
    assert!(text.contains("lens: Some"), "the scene's camera line changed");
    let scene = LoadedScene::parse("tilted-normals-quad-lens", &text, BvhKind::Bvh2, None).unwrap();
    assert!(scene.compiled.thin_lens);
    check_tilted_square(&scene, "thin lens", tilted_radiance());
}

/// Every estimator's mean over the square of `scene` (the tilted square's, named `what`)
/// against its analytic radiance `expected`; through a thin lens, the merging estimators but
/// VCM are left out (their camera rays are VCM's, and they take no lens connections).
pub(crate) fn check_tilted_square(scene: &LoadedScene, what: &str, expected: [f64; 3]) {
    let size = 32;
    let merging = [("PM_RADIUS", ConstValue::F32(0.03))];
    for &(graph, layout, frames) in ESTIMATORS {
        if scene.compiled.thin_lens && matches!(graph, "ppm" | "sppm" | "pbpm") {
            continue;
        }
        let pm = matches!(graph, "ppm" | "sppm" | "pbpm" | "vcm");
        let constants: &[(&str, ConstValue)] = if pm { &merging } else { &[] };
        let r = render(scene, graph, layout, (size, size), 4, frames, 5, constants);
        // Merges reach a radius past the edges, where the density falls: keep away from them.
        let (mean, se, n) = region(&r.image, on_square(size, 0.1));
        assert!(n > 300, "{graph}: {n} pixels on the square");
        // 4 standard errors (seven estimators, three channels: a false failure has odds of
        // about 1 in 750), plus float rounding for PT, whose only noise is the jitter of a
        // constant radiance.
        assert_analytic(&format!("{graph} ({what})"), mean, se, expected, 4.0, 1e-4);
    }
}

/// A RON scene of a unit sphere of `rings` x 2 `rings` quads (two triangles each, fans at the
/// poles) with the sphere's normals at its vertices (`smooth`) or none, diffuse (albedo 0.8),
/// lit by a directional light travelling from the camera (0, -4, 0) to the sphere, so that
/// its radiance is 0.8 / pi * E * cos(angle to -y) and the terminator is the silhouette.
fn sphere_scene(rings: u32, smooth: bool) -> String {
    let mut positions = Vec::new();
    for i in 0..=rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..2 * rings {
            let phi = std::f64::consts::PI * j as f64 / rings as f64;
            let p = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
            positions.push(format!("({:.9}, {:.9}, {:.9})", p[0], p[1], p[2]));
        }
    }
    let at = |i: u32, j: u32| i * 2 * rings + j % (2 * rings);
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..2 * rings {
            // Outward winding: the normal of edges (d theta, d phi) is theta-hat x phi-hat = r-hat.
            if i + 1 < rings {
                indices.push(format!("({}, {}, {})", at(i, j), at(i + 1, j), at(i + 1, j + 1)));
            }
            if i > 0 {
                indices.push(format!("({}, {}, {})", at(i, j), at(i + 1, j + 1), at(i, j + 1)));
            }
        }
    }
    let list = positions.join(", ");
    let normals = if smooth {
        format!("normals: Some([{list}]),")
    } else {
        String::new()
    };
    format!(
        r#"Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    resolution: (48, 48),
    materials: {{ "ball": (diffuse: (0.8, 0.8, 0.8)) }},
    shapes: [Mesh(positions: [{list}], indices: [{}], material: "ball", {normals})],
    lights: [Directional(direction: (0.0, 1.0, 0.0), irradiance: (3.14159265, 3.14159265, 3.14159265))],
)"#,
        indices.join(", ")
    )
}

/// The analytic sphere's scene of [`sphere_scene`].
const ANALYTIC_SPHERE: &str = r#"Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    resolution: (48, 48),
    materials: { "ball": (diffuse: (0.8, 0.8, 0.8)) },
    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: "ball")],
    lights: [Directional(direction: (0.0, 1.0, 0.0), irradiance: (3.14159265, 3.14159265, 3.14159265))],
)"#;

/// The pixels of a 48 x 48 image whose footprint lies within 0.7 of the unit sphere's disk's
/// radius (normals within 44 degrees of the view), where the tessellation moves little.
fn inside_disk(x: u32, y: u32) -> bool {
    let t = (20f64).to_radians().tan();
    [(0, 0), (1, 0), (0, 1), (1, 1)].iter().all(|&(dx, dy)| {
        let nx = (2.0 * (x + dx) as f64 / 48.0 - 1.0) * t;
        let ny = (1.0 - 2.0 * (y + dy) as f64 / 48.0) * t;
        // Distance from the origin to the ray from (0, -4, 0) along (nx, 1, ny).
        let len2 = nx * nx + 1.0 + ny * ny;
        16.0 - 16.0 / len2 < 0.7 * 0.7
    })
}

/// Pixel by pixel on the sphere, the largest difference between two renders in units of
/// their combined standard error, after allowing `allowance` (relative) for what differs on
/// purpose; and the largest relative difference.
fn largest_pixel_difference(a: &Image, b: &Image, allowance: f64) -> (f64, f64) {
    let (mut z_max, mut rel_max) = (0f64, 0f64);
    for y in 0..48 {
        for x in 0..48 {
            if !inside_disk(x, y) {
                continue;
            }
            let i = (y * 48 + x) as usize;
            let (va, vb) = (a.mean[i][0] as f64, b.mean[i][0] as f64);
            let se = (a.variance[i][0] as f64 / a.frames as f64 + b.variance[i][0] as f64 / b.frames as f64).sqrt();
            let d = ((va - vb).abs() - allowance * vb).max(0.0);
            z_max = z_max.max(d / se.max(1e-12));
            rel_max = rel_max.max((va - vb).abs() / vb);
        }
    }
    (z_max, rel_max)
}

#[test]
fn a_sphere_of_triangles_with_vertex_normals_renders_as_the_analytic_sphere() {
    let analytic = LoadedScene::parse("analytic-sphere", ANALYTIC_SPHERE, BvhKind::Bvh2, None).unwrap();
    let reference = render(&analytic, "pt", "NaivePTsk", (48, 48), 16, 16, 3, &[]);
    let (_, _, n) = region(&reference.image, inside_disk);
    assert!(n > 250, "{n} pixels inside the disk");
    // 32 rings: the mesh lies within 1 - cos(pi / 64) = 1.2e-3 of the sphere, so along a
    // camera ray within 44 degrees of the normal its interpolated normal is within about
    // 1.2e-3 radians of the analytic sphere's, 0.12% of the cosine: 0.3% of each pixel's
    // value is allowed for the tessellation; beyond it, 5 combined standard errors (about 300
    // pixels: a false failure has odds under 1 in 5000).
    let smooth = LoadedScene::parse("smooth-sphere", &sphere_scene(32, true), BvhKind::Bvh2, None).unwrap();
    let image = render(&smooth, "pt", "NaivePTsk", (48, 48), 16, 16, 4, &[]).image;
    let (z, rel) = largest_pixel_difference(&image, &reference.image, 3e-3);
    eprintln!("vertex normals: largest pixel difference {rel:.5} ({z:.2} standard errors past 0.3%)");
    assert!(
        z < 5.0,
        "the smooth mesh differs from the analytic sphere: {z} standard errors"
    );
    // The same mesh without its normals is faceted: the check above would catch it.
    let faceted = LoadedScene::parse("faceted-sphere", &sphere_scene(32, false), BvhKind::Bvh2, None).unwrap();
    let image = render(&faceted, "pt", "NaivePTsk", (48, 48), 16, 16, 4, &[]).image;
    let (z, rel) = largest_pixel_difference(&image, &reference.image, 3e-3);
    eprintln!("geometric normals: largest pixel difference {rel:.5} ({z:.2} standard errors past 0.3%)");
    assert!(z > 5.0, "the check cannot tell a faceted sphere ({z} standard errors)");
}
