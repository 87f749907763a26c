//! Feature buffers (`--aov`, lightgraph::aov): on a textured plane seen head-on the albedo is
//! the texture times the base colour, the normal faces the camera, the depth is the analytic
//! distance and the positions lie on the plane; normals are unit length on the Cornell box;
//! the estimator's kernels carry no AOV code; the CLI writes the layers into the EXR.

use crate::cli::{lightgraph, temp_dir};
use crate::common::{gpu, kernel_sources, options};
use lightgraph::aov::{Aov, AovRender};
use lightgraph::run::{LoadedScene, load_scene};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::model::{Camera, FovAxis, Integrator, Look, Material, Pbr, Scene, Shape};
use lightgraph_scenes::texture::{PbrTextures, Texture, TextureRef, Wrap};

const W: u32 = 32;
const H: u32 = 16;
/// Camera height above the plane z = 0, and its horizontal field of view.
const HEIGHT: f32 = 3.0;
const FOV: f32 = 30.0;
/// Samples per pixel in all (4 a frame, 4 frames).
const SAMPLES: f64 = 16.0;

/// A plane z = 0 that fills the view, textured left and right of x = 0 by a 2x1
/// texture (magenta, green; clamped) times the base colour `BASE`, seen from above.
fn textured_plane() -> LoadedScene {
    let texture = Texture {
        name: "two texels".into(),
        width: 2,
        height: 1,
        texels: vec![0xffff00ff, 0xff00ff00],
    };
    let material = Material {
        pbr: Some(Pbr {
            base_color: BASE,
            textures: PbrTextures {
                base_color: Some(TextureRef {
                    wrap: [Wrap::ClampToEdge; 2],
                    ..TextureRef::new(0)
                }),
                ..PbrTextures::default()
            },
            ..Pbr::default()
        }),
        ..Material::default()
    };
    // Half-width 1: the view spans x in +-3 tan(15 deg) = +-0.8, so texture coordinates
    // u = (x + 1) / 2 from 0.1 to 0.9.
    let r = 1.0;
    let s = Scene {
        description: "textured plane".into(),
        camera: Some(Camera {
            position: [0.0, 0.0, HEIGHT],
            look: Look::Forward([0.0, 0.0, -1.0]),
            up: [0.0, 1.0, 0.0],
            fov_degrees: FOV,
            fov_axis: FovAxis::Horizontal,
            lens: None,
        }),
        gltf_camera: None,
        resolution: (W, H),
        materials: [("plane".to_string(), material)].into_iter().collect(),
        shapes: vec![Shape::Mesh {
            positions: vec![[-r, -r, 0.0], [r, -r, 0.0], [r, r, 0.0], [-r, r, 0.0]],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: "plane".into(),
            emission: None,
            uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            normals: None,
            tangents: None,
        }],
        lights: vec![],
        integrator: Integrator::default(),
        media: Default::default(),
        camera_medium: None,
        gltf: None,
        gltf_diffuse: false,
        gltf_instances: Vec::new(),
        mitsuba: None,
        textures: vec![texture],
    };
    LoadedScene {
        name: "textured plane".into(),
        compiled: CompiledScene::with_bvh(&s, BvhKind::Bvh2).unwrap(),
        scene: s,
        load_seconds: 0.0,
    }
}

const BASE: [f32; 3] = [0.5, 0.8, 0.25];

/// Channel `name` of `layers`.
fn channel<'a>(layers: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &layers
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no layer {name}"))
        .1
}

#[test]
fn feature_buffers_of_a_textured_plane_seen_head_on() {
    let scene = textured_plane();
    let opts = options((W, H), 4, 3, &[], Default::default());
    let mut aov = AovRender::new(gpu(), &scene, &opts, &Aov::ALL).unwrap();
    aov.render(0, 4).unwrap();
    let layers = aov.layers().unwrap();
    let (tx, ty) = (
        (FOV.to_radians() / 2.0).tan() as f64,
        (FOV.to_radians() / 2.0).tan() as f64 * H as f64 / W as f64,
    );
    // The distance to the plane along the ray through raster point (x, y).
    let distance = |x: f64, y: f64| {
        let (nx, ny) = (2.0 * x / W as f64 - 1.0, 1.0 - 2.0 * y / H as f64);
        HEIGHT as f64 * (1.0 + (nx * tx).powi(2) + (ny * ty).powi(2)).sqrt()
    };
    let magenta = [BASE[0], 0.0, BASE[2]];
    let green = [0.0, BASE[1], 0.0];
    let (mut left, mut right) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let at = |name: &str| channel(&layers, name)[i] as f64;
            // Depth: the pixel's mean distance (a 16 x 16 grid over it); the jittered mean of
            // 16 samples is off by at most 5 standard errors of the spread over the pixel.
            let grid: Vec<f64> = (0..256)
                .map(|k| {
                    distance(
                        x as f64 + (k % 16) as f64 / 16.0 + 1.0 / 32.0,
                        y as f64 + (k / 16) as f64 / 16.0 + 1.0 / 32.0,
                    )
                })
                .collect();
            let mean = grid.iter().sum::<f64>() / 256.0;
            let spread = grid.iter().cloned().fold(f64::MIN, f64::max) - grid.iter().cloned().fold(f64::MAX, f64::min);
            let tolerance = 5.0 * spread / (12.0 * SAMPLES).sqrt() + 1e-5 * mean;
            assert!(
                (at("depth.Z") - mean).abs() <= tolerance,
                "pixel ({x}, {y}): depth {} vs {mean}",
                at("depth.Z")
            );
            // Positions on the plane, at the depth's distance from the camera.
            let p = [at("position.X"), at("position.Y"), at("position.Z")];
            assert!(p[2].abs() < 1e-4, "pixel ({x}, {y}): position {p:?} off the plane");
            let d = (p[0] * p[0] + p[1] * p[1] + (HEIGHT as f64).powi(2)).sqrt();
            assert!(
                (d - at("depth.Z")).abs() < 1e-3,
                "pixel ({x}, {y}): |position - camera| {d} vs depth"
            );
            // The normal faces the camera.
            let n = [at("normal.X"), at("normal.Y"), at("normal.Z")];
            assert!(
                (n[0].abs() + n[1].abs() + (n[2] - 1.0).abs()) < 1e-5,
                "pixel ({x}, {y}): normal {n:?}"
            );
            // Albedo: texel 0 (u < 1/4, x < -1/2) or texel 1 (u > 3/4) times the base colour;
            // between them bilinear filtering blends, so pixels there are not checked.
            let albedo = [at("albedo.R"), at("albedo.G"), at("albedo.B")];
            let want = match p[0] {
                x if x < -0.55 => magenta,
                x if x > 0.55 => green,
                _ => continue,
            };
            if p[0] < 0.0 {
                left += 1
            } else {
                right += 1
            }
            for c in 0..3 {
                assert!(
                    (albedo[c] - want[c] as f64).abs() < 1e-5,
                    "pixel ({x}, {y}): albedo {albedo:?}, want {want:?}"
                );
            }
        }
    }
    assert!(
        left > 0 && right > 0,
        "albedo checked on {left} pixels left, {right} right"
    );
}

/// On the Cornell box every pixel hits a wall or a block: each normal, averaged over the
/// pixel's samples and renormalised, is unit length.
#[test]
fn normals_are_unit_length_on_the_cornell_box() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let opts = options((16, 16), 2, 5, &[], Default::default());
    let mut aov = AovRender::new(gpu(), &scene, &opts, &[Aov::Normal]).unwrap();
    aov.render(0, 2).unwrap();
    let layers = aov.layers().unwrap();
    let (x, y, z) = (
        channel(&layers, "normal.X"),
        channel(&layers, "normal.Y"),
        channel(&layers, "normal.Z"),
    );
    for i in 0..x.len() {
        let length = (x[i] * x[i] + y[i] * y[i] + z[i] * z[i]).sqrt();
        assert!((length - 1.0).abs() < 1e-5, "pixel {i}: |n| = {length}");
    }
}

/// A render without `--aov` compiles none of the buffers' code into its kernels; the graph
/// `aov` holds it.
#[test]
fn estimator_kernels_carry_no_aov_code() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let pt = kernel_sources("pt", "NaivePTsk", &scene, &[], false);
    assert!(!pt.contains("aov_"), "the path tracer's kernels hold AOV code");
    let aov = kernel_sources("aov", "AOVsk", &scene, &[], false);
    assert!(aov.contains("fn aov_sample") && aov.contains("fn aov_value"));
}

/// `render --aov` writes the layers beside the radiance; unknown buffers and `--gpus` are
/// refused.
#[test]
fn render_writes_the_layers_asked_for() {
    let dir = temp_dir("aov");
    let out = dir.join("aov.exr");
    let o = out.to_str().unwrap();
    let base = [
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "12x8",
        "--frames",
        "2",
        "--out",
        o,
        "--force",
    ];
    let run = lightgraph(&[&base[..], &["--aov", "albedo,depth"]].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let file = lightgraph::output::read_exr(&out).unwrap();
    for name in ["R", "albedo.R", "albedo.G", "albedo.B", "depth.Z"] {
        assert!(file.channels.contains_key(name), "no channel {name}");
    }
    assert!(!file.channels.contains_key("normal.X"));
    let depth = file.channel("depth.Z", &out).unwrap();
    assert!(depth.iter().all(|&d| d > 0.0), "a depth of 0 inside the box");
    let err = crate::cli::fails(&[&base[..], &["--aov", "albedo,speed"]].concat());
    assert!(err.contains("unknown buffer 'speed'"), "{err}");
    let err = crate::cli::fails(&[&base[..], &["--aov", "albedo", "--gpus", "0,0"]].concat());
    assert!(err.contains("--aov renders its buffers on one GPU"), "{err}");
}
