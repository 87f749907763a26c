//! glTF import: a small committed asset (McGuire's Cornell box as glTF) loads with its node
//! transforms, materials and emissive light and renders; broken or unsupported assets give
//! errors that name the file and the problem; Crytek Sponza loads when the shared assets are
//! beside the repository (skipped with a printed reason otherwise).

use crate::common::{assert_finite, data, render};
use lightgraph::render::LoadedScene;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::gpu::light_kind;
use std::path::Path;

fn load(file: &str, text: &str, assets: &Path) -> Result<LoadedScene, String> {
    LoadedScene::parse(file, text, BvhKind::Cwbvh, Some(assets)).map_err(|e| format!("{e:#}"))
}

#[test]
fn the_gltf_cornell_box_loads_and_renders() {
    let file = data("scenes/gltf-cornell.ron");
    let scene = load(
        file.to_str().unwrap(),
        &std::fs::read_to_string(&file).unwrap(),
        &data(""),
    )
    .unwrap();
    let c = &scene.compiled;
    assert_eq!(c.primitives.len(), 36, "the box's triangles");
    let area: Vec<[f32; 3]> = c
        .lights
        .iter()
        .filter(|l| l.kind == light_kind::AREA)
        .map(|l| l.radiance)
        .collect();
    assert_eq!(area.len(), 2, "the emissive quad is two area lights");
    for r in area {
        assert!(
            (r[0] - 17.0).abs() < 1e-4 && (r[1] - 12.0).abs() < 1e-3 && (r[2] - 4.0).abs() < 1e-3,
            "emission x strength: {r:?}"
        );
    }
    assert!(
        scene.scene.materials.values().any(|m| m.two_sided),
        "doubleSided materials stay two-sided"
    );
    let r = render(&scene, "pt", "NaivePTsk", (32, 32), 2, 2, 3, &[]);
    assert_eq!(r.counters["samples_rejected"], 0);
    assert_finite(&r.image, "glTF Cornell box");
    // The walls are lit: the mean of the central pixels is well above black.
    let centre: f32 = (8..24)
        .flat_map(|y| (8..24).map(move |x| (x, y)))
        .map(|(x, y)| r.image.mean[(y * 32 + x) as usize].iter().sum::<f32>())
        .sum::<f32>()
        / 256.0;
    assert!(centre > 0.05, "the box is dark: {centre}");
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-gltf-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SCENE: &str = r#"Scene(gltf: "asset.gltf", camera: (position: (0.0, 0.0, 3.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 1.0, 0.0), fov_degrees: 40.0), lights: [Background(radiance: (1.0, 1.0, 1.0))])"#;

#[test]
fn a_missing_asset_names_the_file_the_root_and_where_assets_come_from() {
    let dir = scratch("missing");
    let e = load("s.ron", SCENE, &dir).err().expect("the scene is refused");
    assert!(
        e.contains("asset.gltf") && e.contains(&dir.display().to_string()) && e.contains("shared/scenes"),
        "{e}"
    );
}

#[test]
fn a_missing_buffer_file_names_the_gltf_file() {
    let dir = scratch("buffer");
    let gltf = std::fs::read_to_string(data("gltf/cornell_box/CornellBox-Original.gltf")).unwrap();
    std::fs::write(dir.join("asset.gltf"), gltf).unwrap();
    let e = load("s.ron", SCENE, &dir).err().expect("the scene is refused");
    assert!(e.contains("asset.gltf"), "{e}");
}

#[test]
fn an_unsupported_required_extension_is_named() {
    let dir = scratch("extension");
    std::fs::write(
        dir.join("asset.gltf"),
        r#"{"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"], "scenes": [{"nodes": []}], "scene": 0}"#,
    )
    .unwrap();
    let e = load("s.ron", SCENE, &dir).err().expect("the scene is refused");
    assert!(
        e.contains("asset.gltf") && e.contains("KHR_draco_mesh_compression"),
        "{e}"
    );
}

#[test]
fn an_asset_without_geometry_is_refused() {
    let dir = scratch("empty");
    std::fs::write(
        dir.join("asset.gltf"),
        r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"name": "empty"}], "scene": 0}"#,
    )
    .unwrap();
    let e = load("s.ron", SCENE, &dir).err().expect("the scene is refused");
    assert!(e.contains("asset.gltf") && e.contains("no triangles"), "{e}");
}

#[test]
fn crytek_sponza_loads_when_the_shared_assets_are_present() {
    let Some(root) = lightgraph::assets::asset_root().filter(|r| r.join("CrytekSponza/glTF/Sponza.gltf").is_file())
    else {
        eprintln!(
            "skipped: CrytekSponza is not under the asset root (set LIGHTGRAPH_ASSETS or put shared/scenes beside the repository)"
        );
        return;
    };
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/gltf/sponza.ron")).unwrap();
    let scene = load("scenes/gltf/sponza.ron", &text, &root).unwrap();
    eprintln!(
        "Sponza: {} triangles loaded with its CWBVH in {:.2} s",
        scene.compiled.primitives.len(),
        scene.load_seconds
    );
    assert_eq!(scene.compiled.primitives.len(), 261_781);
}
