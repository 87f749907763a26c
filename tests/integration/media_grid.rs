//! Heterogeneous media in the path tracer (docs/media.md): density grids tracked by delta
//! tracking (free flights) and ratio tracking (shadow rays). A grid of constant density renders
//! as the homogeneous medium it equals; the transmittance through a purely absorbing density
//! ramp is exp(-∫σt) along each ray, for trilinear and nearest lookups; every layout renders a
//! grid scene alike; and kernels for homogeneous media hold no grid code. The scenes and their
//! `.vol` files are written by the tests.

use crate::common::{assert_analytic, kernel_sources, region, render};
use lightgraph::run::{LoadedScene, load_scene};
use lightgraph_scenes::model::grid::VolumeGrid;
use std::path::PathBuf;

/// A folder of its own for test `name`.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-media-grid-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Mitsuba's `.vol` file of a grid of `res` voxels holding `data` (x fastest).
fn vol(res: [u32; 3], data: &[f32]) -> Vec<u8> {
    VolumeGrid {
        res,
        bbox: [[0.0; 3], [1.0; 3]],
        data: data.to_vec(),
    }
    .to_vol()
}

/// Writes `scene` (RON) as `name.ron` and `grid` as `grid.vol` in `dir`, and loads it.
fn write_and_load(dir: &std::path::Path, name: &str, scene: &str, grid: &[u8]) -> LoadedScene {
    std::fs::write(dir.join("grid.vol"), grid).unwrap();
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, scene).unwrap();
    load_scene(path.to_str().unwrap()).unwrap()
}

/// The grid's map from the unit cube to the box (-1, -1, -1)-(1, 1, 1).
const CUBE: &str = "to_world: ((2.0, 0.0, 0.0, -1.0), (0.0, 2.0, 0.0, -1.0), (0.0, 0.0, 2.0, -1.0))";

/// A sphere of radius `radius` of the medium `medium` in an index-matched boundary, seen from
/// (0, -4, 0) before a uniform background of radiance (1, 2, 4), with a point light when `lit`.
fn sphere_scene(medium: &str, radius: f32, lit: bool) -> String {
    let point = if lit {
        "Point(position: (2.0, -2.0, 2.0), intensity: (6.0, 6.0, 6.0)), "
    } else {
        ""
    };
    format!(
        "Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    resolution: (16, 16),
    media: {{ \"cloud\": ({medium}) }},
    materials: {{ \"boundary\": (null: true, interior: Some(\"cloud\")) }},
    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: {radius:?}, material: \"boundary\")],
    lights: [{point}Background(radiance: (1.0, 2.0, 4.0))],
    integrator: (max_path_length: 64),
)"
    )
}

/// A scattering medium of grey extinction 1.5 and a coloured albedo, forward scattering.
const SCATTERING: &str = "sigma_a: (0.3, 0.6, 0.9), sigma_s: (1.2, 0.9, 0.6), phase: HenyeyGreenstein(g: 0.5)";

#[test]
fn a_grid_of_constant_density_renders_as_its_homogeneous_medium() {
    let dir = folder("constant");
    // Density 1 everywhere in the box around the unit sphere: the same medium.
    let grid = write_and_load(
        &dir,
        "grid",
        &sphere_scene(&format!("{SCATTERING}, grid: (file: \"grid.vol\", {CUBE})"), 1.0, true),
        &vol([2, 2, 2], &[1.0; 8]),
    );
    let homogeneous = write_and_load(&dir, "homogeneous", &sphere_scene(SCATTERING, 1.0, true), &[]);
    let a = render(&grid, "pt", "NaivePTsk", (16, 16), 4, 256, 11, &[]);
    let b = render(&homogeneous, "pt", "NaivePTsk", (16, 16), 4, 256, 12, &[]);
    // The pixels that see the sphere: the centre 8 x 8.
    let centre = |x: u32, y: u32| (4..12).contains(&x) && (4..12).contains(&y);
    let (mean_a, se_a, _) = region(&a.image, centre);
    let (mean_b, se_b, _) = region(&b.image, centre);
    // The two estimates are independent: their difference's standard error combines theirs.
    let se = std::array::from_fn(|c| (se_a[c] * se_a[c] + se_b[c] * se_b[c]).sqrt());
    assert_analytic("constant grid against homogeneous", mean_a, se, mean_b, 4.0, 0.0);
}

/// The mean over pixel (x, y)'s footprint (of `size` pixels, 8 x 8 rays) of the background
/// (1, 2, 4) times exp(-∫ density) along the ray through the box (-1, -1, -1)-(1, 1, 1), the
/// density a function of the grid's y coordinate u in [0, 1].
fn transmitted(x: u32, y: u32, size: u32, density: impl Fn(f64) -> f64) -> [f64; 3] {
    let t = 20f64.to_radians().tan();
    let (n, steps) = (8, 400);
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let px = x as f64 + (i as f64 + 0.5) / n as f64;
            let py = y as f64 + (j as f64 + 0.5) / n as f64;
            let d = [
                (2.0 * px / size as f64 - 1.0) * t,
                1.0,
                (1.0 - 2.0 * py / size as f64) * t,
            ];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let d = d.map(|c| c / len);
            let o = [0.0, -4.0, 0.0];
            // The ray's span inside the box, by slabs.
            let (mut near, mut far) = (0f64, f64::INFINITY);
            for k in 0..3 {
                let (a, b) = ((-1.0 - o[k]) / d[k], (1.0 - o[k]) / d[k]);
                near = near.max(a.min(b));
                far = far.min(a.max(b));
            }
            let mut optical = 0.0;
            if far > near {
                let h = (far - near) / steps as f64;
                for s in 0..steps {
                    let y = o[1] + (near + (s as f64 + 0.5) * h) * d[1];
                    optical += density((y + 1.0) / 2.0) * h;
                }
            }
            sum += (-optical).exp();
        }
    }
    [1.0, 2.0, 4.0].map(|b| b * sum / (n * n) as f64)
}

#[test]
fn transmittance_through_a_density_ramp_is_exp_of_minus_its_integral() {
    let dir = folder("ramp");
    // Eight voxels along y whose densities grow linearly, 0.0625 to 0.9375 (x and z one voxel):
    // trilinear lookups give the density u between the first and last voxel centres, clamped
    // beyond; nearest lookups the voxel's own.
    let voxels: Vec<f32> = (0..8).map(|j| (j as f32 + 0.5) / 8.0).collect();
    let grid = vol([1, 8, 1], &voxels);
    /// A filter's name and the density it reads at a position u in [0, 1] along the ramp.
    type Ramp = (&'static str, fn(f64) -> f64);
    let ramps: [Ramp; 2] = [
        ("Trilinear", |u| u.clamp(1.0 / 16.0, 15.0 / 16.0)),
        ("Nearest", |u| ((u * 8.0).floor().clamp(0.0, 7.0) + 0.5) / 8.0),
    ];
    for (filter, density) in ramps {
        // Purely absorbing, sigma_a 1 per unit density; a boundary sphere holding the box.
        let medium = format!("sigma_a: (1.0, 1.0, 1.0), grid: (file: \"grid.vol\", filter: {filter}, {CUBE})");
        let scene = write_and_load(&dir, filter, &sphere_scene(&medium, 1.8, false), &grid);
        let r = render(&scene, "pt", "NaivePTsk", (16, 16), 4, 256, 5, &[]);
        let inside = |x: u32, y: u32| (3..13).contains(&x) && (3..13).contains(&y);
        let (mean, se, n) = region(&r.image, inside);
        let mut expected = [0f64; 3];
        for y in 3..13 {
            for x in 3..13 {
                let e = transmitted(x, y, 16, density);
                for c in 0..3 {
                    expected[c] += e[c] / n as f64;
                }
            }
        }
        assert_analytic(&format!("{filter} ramp"), mean, se, expected, 3.0, 0.0);
    }
}

#[test]
fn every_path_tracing_layout_renders_a_grid_medium_alike() {
    let dir = folder("layouts");
    let voxels: Vec<f32> = (0..27).map(|i| (i % 5) as f32 * 0.5).collect();
    let scene = write_and_load(
        &dir,
        "grid",
        &sphere_scene(&format!("{SCATTERING}, grid: (file: \"grid.vol\", {CUBE})"), 1.0, true),
        &vol([3, 3, 3], &voxels),
    );
    crate::media::assert_path_tracing_layouts_alike(&scene, "grid medium");
}

#[test]
fn kernels_for_homogeneous_media_hold_no_grid_code_or_buffer() {
    let dir = folder("kernels");
    let grid = write_and_load(
        &dir,
        "grid",
        &sphere_scene(&format!("{SCATTERING}, grid: (file: \"grid.vol\", {CUBE})"), 1.0, true),
        &vol([1, 1, 1], &[1.0]),
    );
    let fog = load_scene("media-fog").unwrap();
    for layout in ["NaivePTsk", "WavefrontPT"] {
        let with = kernel_sources("pt", layout, &grid, &[], false);
        let without = kernel_sources("pt", layout, &fog, &[], false);
        for word in [
            "media_grids",
            "media_density",
            "fn grid_free_flight",
            "fn grid_transmittance",
        ] {
            assert!(with.contains(word), "{layout}: the grid scene's kernels lack {word}");
            assert!(!without.contains(word), "{layout}: media-fog's kernels hold {word}");
        }
    }
}
