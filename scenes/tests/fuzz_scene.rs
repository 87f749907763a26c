//! Fuzzing of RON scene files with proptest: mutated scene files (the built-in Cornell boxes,
//! Sponza and the test scenes) and scenes generated field by field (odd numbers, meshes with
//! any indices, unknown materials) go through [`parse_scene`], [`resolve_gltf`] (asset root
//! `tests/data`, which holds the glTF Cornell box) and [`CompiledScene::with_bvh`] for both BVH
//! kinds.
//!
//! Properties: no input panics; every refusal is an error whose message is not empty; a scene
//! error names the scene file, and a RON syntax or schema error its line and column (within the
//! file).
//!
//! Bound: 4000 mutated and 3000 generated scenes, about ten seconds in a debug build;
//! `LIGHTGRAPH_FUZZ_CASES=N cargo test -p lightgraph-scenes --test fuzz_scene -- --nocapture`
//! runs N inputs per test (and prints the counts), `LIGHTGRAPH_FUZZ_SEED=K` other inputs.

#[path = "../../engine/tests/common/fuzz.rs"]
mod fuzz;

use fuzz::{Mutated, Outcome, RON, check_located, edits, fuzz};
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::model::Scene;
use lightgraph_scenes::{CompiledScene, SceneError, parse_scene, resolve_gltf};
use proptest::prelude::*;
use proptest::sample::Index;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// The seed scenes: (file name, text).
fn seeds() -> &'static [(String, String)] {
    static SEEDS: OnceLock<Vec<(String, String)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let mut files = Vec::new();
        for dir in ["scenes/cornell", "scenes/gltf", "tests/data/scenes"] {
            for entry in std::fs::read_dir(workspace().join(dir)).unwrap() {
                files.push(entry.unwrap().path());
            }
        }
        files.sort();
        files
            .iter()
            .map(|p| {
                let name = p.strip_prefix(workspace()).unwrap().display().to_string();
                (name, std::fs::read_to_string(p).unwrap())
            })
            .collect()
    })
}

/// Checks a scene error's properties (see the file's documentation).
fn check_error(e: &SceneError, file: &str, text: &str) -> Result<Outcome, String> {
    let message = e.to_string();
    if e.file != file || e.message.trim().is_empty() {
        return Err(format!("'{message}' does not name the file {file} and a problem"));
    }
    let ron_error = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<Scene>(text)
        .is_err();
    if e.at.is_some() || ron_error {
        check_located(&message, file, text.lines().count())?;
    }
    Ok(Outcome::Refused(message))
}

/// Parses, resolves the glTF asset and compiles with both BVH kinds.
fn check(file: &str, text: &str) -> Result<Outcome, String> {
    let mut scene = match parse_scene(file, text) {
        Ok(s) => s,
        Err(e) => return check_error(&e, file, text),
    };
    if let Err(e) = resolve_gltf(&mut scene, file, Some(&workspace().join("tests/data"))) {
        return check_error(&e, file, text);
    }
    for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
        match CompiledScene::with_bvh(&scene, kind) {
            Ok(compiled) => {
                let (w, h) = scene.resolution;
                compiled.resources(&CompiledScene::camera(&scene, w, h));
            }
            Err(e) if e.trim().is_empty() => return Err("an empty BVH error".into()),
            Err(e) => return Ok(Outcome::Refused(e)),
        }
    }
    Ok(Outcome::Ok)
}

#[test]
fn fuzz_scene_files() {
    let mutated = (any::<Index>(), edits(3)).prop_map(|(i, edits)| {
        let (file, text) = &seeds()[i.index(seeds().len())];
        Mutated::new(file, text, edits, &RON)
    });
    fuzz("scene", 4000, mutated, |m| check(&m.file, &m.text));
}

/// A float in `range` or, one time in 60, zero, huge, tiny, infinite or NaN.
fn float_in(range: std::ops::Range<f32>) -> impl Strategy<Value = String> {
    let odd = prop::sample::select(vec![
        0.0,
        -0.0,
        1e30,
        -1e30,
        1e-40,
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ]);
    prop_oneof![60 => range, 1 => odd].prop_map(|v| format!("{v:?}"))
}

fn float() -> impl Strategy<Value = String> {
    float_in(-4.0..4.0)
}

fn vec3() -> impl Strategy<Value = String> {
    [float(), float(), float()].prop_map(|[x, y, z]| format!("({x}, {y}, {z})"))
}

/// A count in 1..8 or, one time in 20, 0 or huge.
fn int() -> impl Strategy<Value = u32> {
    prop_oneof![20 => 1..8u32, 1 => prop::sample::select(vec![0, u32::MAX, 1 << 31, 65536])]
}

fn material_name() -> impl Strategy<Value = &'static str> {
    prop_oneof![20 => Just("m"), 10 => Just("n"), 1 => Just("unknown")]
}

fn emission() -> impl Strategy<Value = String> {
    prop::option::of(vec3()).prop_map(|e| e.map_or(String::new(), |e| format!(", emission: {e}")))
}

fn shape() -> impl Strategy<Value = String> {
    let index = || prop_oneof![20 => 0..3u32, 1 => prop::sample::select(vec![3, 7, u32::MAX])];
    let mesh = (
        prop::collection::vec(vec3(), 2..7),
        prop::collection::vec([index(), index(), index()], 0..5),
    );
    prop_oneof![
        ([vec3(), vec3(), vec3()], material_name(), emission())
            .prop_map(|([a, b, c], m, e)| format!("Triangle(vertices: ({a}, {b}, {c}), material: \"{m}\"{e})")),
        ([vec3(), vec3(), vec3(), vec3()], material_name(), emission())
            .prop_map(|([a, b, c, d], m, e)| format!("Quad(corners: ({a}, {b}, {c}, {d}), material: \"{m}\"{e})")),
        (mesh, material_name(), emission()).prop_map(|((p, i), m, e)| {
            let i: Vec<String> = i.iter().map(|[a, b, c]| format!("({a}, {b}, {c})")).collect();
            format!(
                "Mesh(positions: [{}], indices: [{}], material: \"{m}\"{e})",
                p.join(", "),
                i.join(", ")
            )
        }),
        (vec3(), float_in(0.01..4.0), material_name())
            .prop_map(|(c, r, m)| format!("Sphere(center: {c}, radius: {r}, material: \"{m}\")")),
    ]
}

fn light() -> impl Strategy<Value = String> {
    prop_oneof![
        (vec3(), vec3()).prop_map(|(p, i)| format!("Point(position: {p}, intensity: {i})")),
        (vec3(), vec3()).prop_map(|(d, i)| format!("Directional(direction: {d}, irradiance: {i})")),
        (vec3(), float()).prop_map(|(r, s)| format!("Background(radiance: {r}, scale: {s})")),
    ]
}

fn material() -> impl Strategy<Value = String> {
    (vec3(), vec3(), float(), vec3(), float(), any::<bool>()).prop_map(|(d, p, e, m, ior, two)| {
        format!("(diffuse: {d}, phong: {p}, phong_exponent: {e}, mirror: {m}, ior: {ior}, two_sided: {two})")
    })
}

/// A whole scene, field by field.
fn scene() -> impl Strategy<Value = String> {
    let camera = (
        vec3(),
        prop::sample::select(vec!["Target", "Forward"]),
        vec3(),
        vec3(),
        float_in(1.0..179.0),
        prop::sample::select(vec!["Horizontal", "Vertical", "Smaller"]),
    )
        .prop_map(|(p, look, at, up, fov, axis)| {
            format!("(position: {p}, look: {look}({at}), up: {up}, fov_degrees: {fov}, fov_axis: {axis})")
        });
    let integrator = (
        int(),
        prop::option::of((int(), float())),
        prop::sample::select(vec!["Balance", "Power"]),
    )
        .prop_map(|(n, rr, mis)| {
            let rr = rr.map_or("Albedo".to_string(), |(s, m)| {
                format!("Throughput(start: {s}, max: {m})")
            });
            format!("(max_path_length: {n}, russian_roulette: {rr}, mis: {mis})")
        });
    (
        camera,
        (int(), int()),
        [material(), material()],
        prop::collection::vec(shape(), 1..6),
        prop::collection::vec(light(), 0..3),
        integrator,
    )
        .prop_map(|(camera, (w, h), [m, n], shapes, lights, integrator)| {
            format!(
                "Scene(\n    camera: {camera},\n    resolution: ({w}, {h}),\n    materials: {{ \"m\": {m}, \"n\": {n} }},\n    \
                 shapes: [\n        {}\n    ],\n    lights: [{}],\n    integrator: {integrator},\n)\n",
                shapes.join(",\n        "),
                lights.join(", ")
            )
        })
}

#[test]
fn fuzz_generated_scenes() {
    let generated = scene().prop_map(|text| Mutated::new("generated.ron", &text, Vec::new(), &RON));
    fuzz("generated scene", 3000, generated, |m| check(&m.file, &m.text));
}

#[test]
fn seeds_are_checked() {
    // The built-in scenes compile; the test scenes compile or give good errors (no-light.ron,
    // and Sponza, whose asset lies outside tests/data).
    for (file, text) in seeds() {
        let outcome = check(file, text).unwrap();
        assert!(
            outcome == Outcome::Ok || !file.starts_with("scenes/cornell"),
            "{file}: {outcome:?}"
        );
    }
}
