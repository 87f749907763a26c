//! The stress scenes (`scenes/stress/`) and the invariant each must keep. Expected values are
//! computed from the parsed scene (its lights, materials and geometry), so a scene file and
//! its invariant cannot drift apart.

use lightgraph_scenes::gpu::GpuCamera;
use lightgraph_scenes::model::{Light, Scene, Shape};

/// An interval of expected values per pixel, or `None` where a pixel is not checked.
pub type Expected = Vec<Option<([f64; 3], [f64; 3])>>;

/// What a stress scene must show.
#[derive(Debug, Clone, Copy)]
pub enum Invariant {
    /// Pixel expectations computed from the scene, compared with region means.
    Expect(Expectation),
    /// The image of another scene, rendered with an independent seed, region by region.
    SameAs(&'static str),
    /// Another scene's image times a factor, pixel by pixel, to float rounding (same seed,
    /// so the same paths).
    ScaledCopyOf(&'static str, f64),
    /// Exactly the scene's background radiance at every pixel (relative tolerance).
    Background(f64),
    /// A lossless object in a uniform environment: every pixel is the environment's radiance,
    /// none brighter beyond rounding; a path lost on the way (a sample of 0) shows as a deficit,
    /// and at most this fraction of the samples may be lost (see docs/testing.md, "Stress suite").
    Furnace(f64),
    /// An enclosure that hides a bright environment: black, but for rays that slip through
    /// the single-precision triangle test at an edge, each of which sees the environment. At
    /// most this fraction of the samples may (see docs/testing.md, "Stress suite").
    Enclosed(f64),
}

/// Closed-form expectations.
#[derive(Debug, Clone, Copy)]
pub enum Expectation {
    /// A closed box whose every wall emits Le and reflects diffusely with albedo ρ:
    /// Le / (1 − ρ) everywhere (the first shape gives Le and ρ).
    EmissiveEnclosure,
    /// A Phong sphere (the first shape) in a uniform background L: k L cos θ to the factor
    /// (n + 2) / (n + 1) where the whole pixel sees the sphere, L where it sees none of it,
    /// and at most L everywhere.
    PhongFurnace,
    /// A diffuse plane (the first shape, a quad at z = 0) under a uniform sky L: ρ L where the
    /// whole pixel sees the plane, L where it sees only sky.
    SkyOverPlane,
    /// A point light at height h above a diffuse plane at z = 0 (the first shape):
    /// ρ I h / (π (d² + h²)^1.5) at distance d from its foot, averaged over each pixel; the
    /// pixels within three pixel widths of the foot are not checked.
    PointLightOverPlane,
    /// A scene that absorbs nothing in a uniform environment L, where samples are not each L
    /// (a medium's next-event estimation shares the environment with phase sampling by MIS):
    /// L everywhere, region by region.
    Environment,
}

/// A stress scene and its invariant.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// Built-in scene name.
    pub scene: &'static str,
    /// What it must show.
    pub invariant: Invariant,
    /// Resolution at scale 1.
    pub resolution: (u32, u32),
}

/// Every stress case.
pub fn cases() -> Vec<Case> {
    use Expectation::*;
    use Invariant::*;
    let case = |scene, invariant, resolution| Case {
        scene,
        invariant,
        resolution,
    };
    vec![
        case("stress-emissive-box-0.99", Expect(EmissiveEnclosure), (8, 8)),
        case("stress-emissive-box-0.999", Expect(EmissiveEnclosure), (8, 8)),
        case("stress-cornell-scaled-1e-4", SameAs("cornell-diffuse"), (32, 32)),
        case("stress-cornell-scaled-1e4", SameAs("cornell-diffuse"), (32, 32)),
        case(
            "stress-area-light-1e-8",
            ScaledCopyOf("cornell-diffuse", 1e-8),
            (32, 32),
        ),
        case("stress-area-light-1e8", ScaledCopyOf("cornell-diffuse", 1e8), (32, 32)),
        case(
            "stress-point-light-1e-8",
            ScaledCopyOf("cornell-glossy-point", 1e-8),
            (32, 32),
        ),
        case(
            "stress-point-light-1e8",
            ScaledCopyOf("cornell-glossy-point", 1e8),
            (32, 32),
        ),
        case("stress-degenerate-mesh", SameAs("cornell-diffuse"), (32, 32)),
        case("stress-grazing-camera", Expect(SkyOverPlane), (32, 32)),
        case("stress-camera-inside-object", Enclosed(1e-7), (32, 32)),
        case("stress-camera-facing-away", Background(1e-6), (32, 32)),
        case("stress-phong-1e5", Expect(PhongFurnace), (32, 32)),
        case("stress-glass-ior-1.0001", Furnace(1e-7), (32, 32)),
        case("stress-glass-ior-3", Furnace(1e-7), (32, 32)),
        case("stress-ggx-roughness-1e-4", Furnace(1e-7), (32, 32)),
        case("stress-point-light-1e-6-above", Expect(PointLightOverPlane), (32, 32)),
        case("stress-media-scaled-1e-4", SameAs("media-sphere"), (32, 32)),
        case("stress-media-scaled-1e4", SameAs("media-sphere"), (32, 32)),
        case("stress-media-fog-1e-6", SameAs("cornell-diffuse"), (32, 32)),
        case("stress-media-furnace-g0.999", Expect(Environment), (16, 16)),
        case("stress-media-furnace-g-0.999", Expect(Environment), (16, 16)),
    ]
}

/// The uniform background radiance of a scene (zero without one).
pub fn background(scene: &Scene) -> [f64; 3] {
    scene
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Background { radiance, scale } => Some(radiance.map(|v| (v * scale) as f64)),
            _ => None,
        })
        .unwrap_or([0.0; 3])
}

/// Unit direction of the camera ray through raster position (x, y), as camera.wgsl makes it.
fn direction(cam: &GpuCamera, x: f64, y: f64) -> [f64; 3] {
    let (nx, ny) = (2.0 * x / cam.width as f64 - 1.0, 1.0 - 2.0 * y / cam.height as f64);
    let d: [f64; 3] = std::array::from_fn(|k| cam.forward[k] as f64 + nx * cam.right[k] as f64 + ny * cam.up[k] as f64);
    let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
    d.map(|v| v / len)
}

fn origin(cam: &GpuCamera) -> [f64; 3] {
    cam.position.map(|v| v as f64)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Where a camera ray meets the plane z = 0, if ahead.
fn on_plane(o: [f64; 3], d: [f64; 3]) -> Option<[f64; 3]> {
    let t = -o[2] / d[2];
    (t > 0.0).then(|| std::array::from_fn(|k| o[k] + t * d[k]))
}

/// The four corners of pixel (x, y) in raster coordinates.
fn corners(x: u32, y: u32) -> [(f64, f64); 4] {
    let (x, y) = (x as f64, y as f64);
    [(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)]
}

fn first_shape(scene: &Scene) -> &Shape {
    scene.shapes.first().expect("a stress scene has shapes")
}

fn diffuse_albedo(scene: &Scene) -> f64 {
    scene.materials[first_shape(scene).material()].diffuse[0] as f64
}

impl Expectation {
    /// The expected interval of every pixel of `scene` seen through `cam`.
    pub fn expected(self, scene: &Scene, cam: &GpuCamera) -> Expected {
        let (w, h) = (cam.width as u32, cam.height as u32);
        let pixels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
        let o = origin(cam);
        let bg = background(scene);
        match self {
            Expectation::Environment => pixels.map(|_| Some((bg, bg))).collect(),
            Expectation::EmissiveEnclosure => {
                let le = match first_shape(scene) {
                    Shape::Quad { emission: Some(e), .. } => e[0] as f64,
                    other => panic!("the enclosure's first shape is an emissive quad, not {other:?}"),
                };
                let v = le / (1.0 - diffuse_albedo(scene));
                pixels.map(|_| Some(([v; 3], [v; 3]))).collect()
            }
            Expectation::PhongFurnace => {
                let (center, radius, material) = match first_shape(scene) {
                    Shape::Sphere {
                        center,
                        radius,
                        material,
                    } => (center.map(|v| v as f64), *radius as f64, material),
                    other => panic!("the furnace's first shape is a sphere, not {other:?}"),
                };
                let m = &scene.materials[material];
                let (k, n) = (m.phong[0] as f64, m.phong_exponent as f64);
                // Cosine at the sphere for each corner ray, or None where it misses.
                let cosine = |d: [f64; 3]| {
                    let oc: [f64; 3] = std::array::from_fn(|i| o[i] - center[i]);
                    let b = dot(oc, d);
                    let disc = b * b - (dot(oc, oc) - radius * radius);
                    (disc >= 0.0).then(|| {
                        let t = -b - disc.sqrt();
                        let p: [f64; 3] = std::array::from_fn(|i| oc[i] + t * d[i]);
                        -dot(p, d) / radius
                    })
                };
                pixels
                    .map(|(x, y)| {
                        let c: Vec<Option<f64>> = corners(x, y)
                            .iter()
                            .map(|&(cx, cy)| cosine(direction(cam, cx, cy)))
                            .collect();
                        Some(if c.iter().all(Option::is_none) {
                            (bg, bg)
                        } else if c.iter().all(Option::is_some) {
                            // The cosine falls away from the point that faces the camera, so over
                            // a pixel its least value is at a corner; its greatest is found on a
                            // 9 x 9 grid, plus the largest step between grid neighbours.
                            let min = c.iter().flatten().fold(1.0f64, |a, &b| a.min(b));
                            let grid: Vec<f64> = (0..81)
                                .map(|i| {
                                    let (u, v) = ((i % 9) as f64 / 8.0, (i / 9) as f64 / 8.0);
                                    cosine(direction(cam, x as f64 + u, y as f64 + v)).unwrap_or(0.0)
                                })
                                .collect();
                            let step = (0..81)
                                .filter(|i| i % 9 < 8)
                                .map(|i| (grid[i] - grid[i + 1]).abs())
                                .chain((0..72).map(|i| (grid[i] - grid[i + 9]).abs()))
                                .fold(0.0f64, f64::max);
                            let max = (grid.iter().fold(0.0f64, |a, &b| a.max(b)) + step).min(1.0);
                            // Below a cosine of 0.05 part of the narrow lobe may fall under the
                            // horizon, where samples are void.
                            let lo = if min > 0.05 { min * (1.0 - 1e-3) } else { 0.0 };
                            (bg.map(|l| l * k * lo), bg.map(|l| l * k * max * (n + 2.0) / (n + 1.0)))
                        } else {
                            ([0.0; 3], bg)
                        })
                    })
                    .collect()
            }
            Expectation::SkyOverPlane => {
                let half = match first_shape(scene) {
                    Shape::Quad { corners, .. } => corners
                        .iter()
                        .map(|c| c[0].abs().min(c[1].abs()) as f64)
                        .fold(f64::MAX, f64::min),
                    other => panic!("the plane is a quad, not {other:?}"),
                };
                let rho = diffuse_albedo(scene);
                pixels
                    .map(|(x, y)| {
                        let floor = corners(x, y).map(|(cx, cy)| {
                            on_plane(o, direction(cam, cx, cy)).is_some_and(|p| p[0].abs() < half && p[1].abs() < half)
                        });
                        match (floor.iter().all(|&f| f), floor.iter().any(|&f| f)) {
                            (true, _) => Some((bg.map(|l| l * rho), bg.map(|l| l * rho))),
                            (false, false) => Some((bg, bg)),
                            _ => None,
                        }
                    })
                    .collect()
            }
            Expectation::PointLightOverPlane => {
                let (light, intensity) = scene
                    .lights
                    .iter()
                    .find_map(|l| match l {
                        Light::Point { position, intensity } => Some((position.map(|v| v as f64), intensity[0] as f64)),
                        _ => None,
                    })
                    .expect("the scene has a point light");
                let (rho, height) = (diffuse_albedo(scene), light[2]);
                let radiance = |p: [f64; 3]| {
                    let d2 = (p[0] - light[0]).powi(2) + (p[1] - light[1]).powi(2);
                    rho * intensity * height / (std::f64::consts::PI * (d2 + height * height).powf(1.5))
                };
                // The pixel width on the plane at the image centre, for the exclusion zone.
                let hit = |x: f64, y: f64| on_plane(o, direction(cam, x, y)).expect("the camera looks at the plane");
                let (a, b) = (
                    hit(w as f64 / 2.0, h as f64 / 2.0),
                    hit(w as f64 / 2.0 + 1.0, h as f64 / 2.0),
                );
                let pixel = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                const SUB: u32 = 16;
                pixels
                    .map(|(x, y)| {
                        let centre = hit(x as f64 + 0.5, y as f64 + 0.5);
                        let d = ((centre[0] - light[0]).powi(2) + (centre[1] - light[1]).powi(2)).sqrt();
                        if d < 3.0 * pixel {
                            return None;
                        }
                        let mut sum = 0.0;
                        for j in 0..SUB {
                            for i in 0..SUB {
                                let (sx, sy) = ((i as f64 + 0.5) / SUB as f64, (j as f64 + 0.5) / SUB as f64);
                                sum += radiance(hit(x as f64 + sx, y as f64 + sy));
                            }
                        }
                        // The midpoint rule over 16 x 16 points is within 1e-3 of the pixel's
                        // mean three pixels out from the peak, where it is least accurate.
                        let v = sum / (SUB * SUB) as f64;
                        Some(([v * (1.0 - 2e-3); 3], [v * (1.0 + 2e-3); 3]))
                    })
                    .collect()
            }
        }
    }
}
