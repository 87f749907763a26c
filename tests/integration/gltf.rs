//! glTF import: a small committed asset (McGuire's Cornell box as glTF) loads with its node
//! transforms, materials and emissive light and renders; broken or unsupported assets give
//! errors that name the file and the problem; Crytek Sponza loads from the shared assets (the
//! assets tier: ignored unless `cargo xtask test` finds the asset root).

use crate::common::{assert_finite, data, render, shared_assets};
use lightgraph::run::LoadedScene;
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

/// The glTF Cornell box placed four times: once by a turn and a move, once as the asset puts
/// it and twice by a grid.
const PLACED: &str = r#"Scene(
    gltf: "gltf/cornell_box/CornellBox-Original.gltf",
    gltf_instances: [
        At(translate: (3.0, 0.0, 0.0), rotate_y_degrees: 180.0),
        Grid(counts: (1, 1, 2), spacing: (0.0, 0.0, -4.0)),
        At(scale: 0.5),
    ],
    camera: (position: (0.0, 1.0, 8.0), look: Target((0.0, 1.0, 0.0)), up: (0.0, 1.0, 0.0), fov_degrees: 60.0),
    resolution: (16, 16),
)"#;

#[test]
fn gltf_instances_place_copies_of_the_asset() {
    let scene = load("placed.ron", PLACED, &data("")).unwrap();
    assert_eq!(
        scene.compiled.primitives.len(),
        4 * 36,
        "four copies of the box's triangles"
    );
    let area = scene
        .compiled
        .lights
        .iter()
        .filter(|l| l.kind == light_kind::AREA)
        .count();
    assert_eq!(area, 4 * 2, "each copy's emissive quad is two area lights");
    // The box spans x and z in about [-1, 1]: the moved copy reaches x 3 + 1, the grid's
    // second copy z -4 - 1, the half-size copy y 1 at most.
    let points: Vec<[f32; 3]> = scene
        .scene
        .shapes
        .iter()
        .flat_map(|s| match s {
            lightgraph_scenes::model::Shape::Mesh { positions, .. } => positions.clone(),
            _ => Vec::new(),
        })
        .collect();
    let max_x = points.iter().map(|p| p[0]).fold(f32::MIN, f32::max);
    let min_z = points.iter().map(|p| p[2]).fold(f32::MAX, f32::min);
    assert!((3.9..4.1).contains(&max_x), "max x {max_x}");
    assert!((-5.1..-4.9).contains(&min_z), "min z {min_z}");
    let r = render(&scene, "pt", "NaivePTsk", (16, 16), 1, 1, 3, &[]);
    assert_finite(&r.image, "placed Cornell boxes");
}

/// The error of loading `text` as `file`, with the test data as asset root.
fn load_error(file: &str, text: &str) -> String {
    match load(file, text, &data("")) {
        Ok(_) => panic!("{file} loaded"),
        Err(e) => e,
    }
}

#[test]
fn bad_gltf_instances_are_errors_at_their_line() {
    let zero = PLACED.replace("At(scale: 0.5)", "At(scale: 0.0)");
    let e = load_error("placed.ron", &zero);
    assert!(
        e.contains("placed.ron:6:") && e.contains("scale 0 is not positive"),
        "{e}"
    );
    let none = PLACED.replace("counts: (1, 1, 2)", "counts: (1, 0, 2)");
    let e = load_error("placed.ron", &none);
    assert!(e.contains("placed.ron:5:") && e.contains("place no copy"), "{e}");
    let without = PLACED.replace("gltf: \"gltf/cornell_box/CornellBox-Original.gltf\",", "shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: \"m\")], materials: {\"m\": (diffuse: (0.5, 0.5, 0.5))}, lights: [Point(position: (0.0, 3.0, 0.0), intensity: (1.0, 1.0, 1.0))],");
    let e = load_error("placed.ron", &without);
    assert!(e.contains("the scene has none"), "{e}");
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
#[ignore = "needs the shared assets (CrytekSponza): cargo xtask test --assets"]
fn crytek_sponza_loads_from_the_shared_assets() {
    let root = shared_assets(&["CrytekSponza"]);
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/gltf/sponza.ron")).unwrap();
    let scene = load("scenes/gltf/sponza.ron", &text, &root).unwrap();
    eprintln!(
        "Sponza: {} triangles loaded with its CWBVH in {:.2} s",
        scene.compiled.primitives.len(),
        scene.load_seconds
    );
    assert_eq!(scene.compiled.primitives.len(), 261_781);
    // Its plants and chains (three materials) are alpha-masked, and every material but the
    // curtains' flat colours samples a base-colour texture.
    let masked = scene
        .compiled
        .materials
        .iter()
        .filter(|m| m.flags & lightgraph_scenes::gpu::material_flags::ALPHA_MASK != 0)
        .count();
    assert_eq!(masked, 3);
    assert!(!scene.scene.textures.is_empty());
    assert_eq!(
        scene.compiled.attributes.len(),
        scene.compiled.primitives.len(),
        "texture coordinates and normals per triangle"
    );
}

/// Writes `quad.gltf` (with `quad.bin` and `paint.png`) to `dir`: one quad with normals and
/// texture coordinates, held by a node that moves it to z = -2 and mirrors it in x; a
/// material with every factor lightgraph imports and a 2x2 base-colour texture with
/// KHR_texture_transform; with `camera`, a node "eye" at (0, 0, 3) turned 90 degrees about
/// +Y holding a perspective camera "lens". No light.
fn write_quad_gltf(dir: &Path, camera: bool) -> std::path::PathBuf {
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let normals: [[f32; 3]; 4] = [[0.6, 0.0, 0.8], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.6, 0.8]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = Vec::new();
    bin.extend_from_slice(bytemuck::cast_slice(&positions));
    bin.extend_from_slice(bytemuck::cast_slice(&normals));
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    bin.extend_from_slice(bytemuck::cast_slice(&indices));
    std::fs::write(dir.join("quad.bin"), &bin).unwrap();
    image::RgbaImage::from_raw(2, 2, PAINT.to_vec())
        .unwrap()
        .save(dir.join("paint.png"))
        .unwrap();
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let (camera_node, cameras) = if camera {
        (
            format!(r#", {{"name": "eye", "camera": 0, "translation": [0, 0, 3], "rotation": [0, {s}, 0, {s}]}}"#),
            r#""cameras": [{"name": "lens", "type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 2.0, "znear": 0.1}}],"#,
        )
    } else {
        (String::new(), "")
    };
    let nodes = if camera { "[0, 1]" } else { "[0]" };
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_texture_transform", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength"],
  "scene": 0,
  "scenes": [{{"nodes": {nodes}}}],
  "nodes": [{{"name": "quad", "mesh": 0, "translation": [0, 0, -2], "scale": [-1, 1, 1]}}{camera_node}],
  {cameras}
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3, "material": 0}}]}}],
  "materials": [{{
    "name": "paint",
    "doubleSided": true,
    "alphaMode": "MASK",
    "alphaCutoff": 0.3,
    "emissiveFactor": [0.5, 0.25, 0.0],
    "pbrMetallicRoughness": {{
      "baseColorFactor": [0.8, 0.6, 0.4, 0.9],
      "metallicFactor": 0.7,
      "roughnessFactor": 0.2,
      "baseColorTexture": {{"index": 0, "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0], "scale": [2, 1]}}}}}}
    }},
    "extensions": {{
      "KHR_materials_emissive_strength": {{"emissiveStrength": 4.0}},
      "KHR_materials_transmission": {{"transmissionFactor": 0.25}},
      "KHR_materials_ior": {{"ior": 1.33}}
    }}
  }}],
  "textures": [{{"source": 0, "sampler": 0}}],
  "samplers": [{{"wrapS": 33071, "wrapT": 33648}}],
  "images": [{{"uri": "paint.png"}}],
  "buffers": [{{"uri": "quad.bin", "byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 128, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        len = bin.len()
    );
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// The 2x2 RGBA texels of `paint.png`.
const PAINT: [u8; 16] = [255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 10, 20, 30, 40];

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn gltf_vertex_attributes_materials_textures_and_cameras_import() {
    use lightgraph_scenes::model::{FovAxis, Look, Shape};
    use lightgraph_scenes::texture::Wrap;
    let dir = scratch("quad");
    let imported = lightgraph_scenes::gltf::import(&write_quad_gltf(&dir, true)).unwrap();
    let [
        Shape::Mesh {
            positions,
            indices,
            uvs,
            normals,
            material,
            emission,
            tangents: None,
        },
    ] = &imported.shapes[..]
    else {
        panic!("one mesh: {:?}", imported.shapes)
    };
    // Mirrored in x and moved to z = -2; the mirror re-winds the triangles so they keep facing
    // +z, and normals map by the inverse transpose (x negated).
    assert_eq!(positions[1], [-1.0, 0.0, -2.0]);
    assert_eq!(indices, &vec![[0, 2, 1], [0, 3, 2]]);
    let normals = normals.as_ref().expect("normals");
    assert!(
        close(normals[0], [-0.6, 0.0, 0.8]) && close(normals[3], [0.0, 0.6, 0.8]),
        "{normals:?}"
    );
    assert_eq!(uvs.as_ref().expect("texture coordinates")[0], [0.0, 1.0]);
    assert_eq!(material, "gltf:paint");
    assert_eq!(*emission, Some([2.0, 1.0, 0.0]), "emissive factor x strength");
    let m = &imported.materials["gltf:paint"];
    assert!(m.two_sided);
    let p = m.pbr.as_ref().expect("a metallic-roughness material");
    assert_eq!(
        (
            p.base_color,
            p.alpha,
            p.metallic,
            p.roughness,
            p.transmission,
            p.ior,
            p.alpha_cutoff
        ),
        ([0.8, 0.6, 0.4], 0.9, 0.7, 0.2, 0.25, 1.33, Some(0.3))
    );
    let t = p.textures.base_color.expect("a base colour texture");
    assert_eq!(t.wrap, [Wrap::ClampToEdge, Wrap::MirroredRepeat]);
    assert_eq!(t.transform, [[2.0, 0.0, 0.5], [0.0, 1.0, 0.0]]);
    assert_eq!(p.textures.metallic_roughness, None);
    let texture = &imported.textures[t.texture as usize];
    assert_eq!((texture.width, texture.height), (2, 2));
    assert_eq!(bytemuck::cast_slice::<u32, u8>(&texture.texels), &PAINT[..]);
    let [camera] = &imported.cameras[..] else {
        panic!("one camera: {:?}", imported.cameras)
    };
    assert_eq!(camera.names, vec!["lens".to_string(), "eye".to_string()]);
    assert_eq!(camera.aspect_ratio, Some(2.0));
    assert!(close(camera.camera.position, [0.0, 0.0, 3.0]));
    let Look::Forward(forward) = camera.camera.look else {
        panic!("a direction")
    };
    assert!(
        close(forward, [-1.0, 0.0, 0.0]),
        "-Z turned 90 degrees about +Y: {forward:?}"
    );
    assert!((camera.camera.fov_degrees - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!(camera.camera.fov_axis, FovAxis::Vertical);
}

#[test]
fn a_scene_file_takes_its_camera_from_the_gltf_by_name_or_index() {
    let dir = scratch("camera");
    write_quad_gltf(&dir, true);
    let text = |camera: &str| {
        format!(r#"Scene(gltf: "quad.gltf", gltf_camera: {camera}, lights: [Background(radiance: (1.0, 1.0, 1.0))])"#)
    };
    for camera in [r#"Name("eye")"#, r#"Name("lens")"#, "Index(0)"] {
        let scene = load("s.ron", &text(camera), &dir).unwrap();
        let c = scene.scene.camera.as_ref().expect("the glTF camera");
        assert!(close(c.position, [0.0, 0.0, 3.0]), "{camera}: {c:?}");
    }
    let e = load("s.ron", &text("Index(3)"), &dir).err().expect("no camera 3");
    assert!(
        e.contains("quad.gltf") && e.contains("Index(3)") && e.contains("0 [\"lens\", \"eye\"]"),
        "{e}"
    );
    let e = load("s.ron", r#"Scene(gltf: "quad.gltf", lights: [])"#, &dir)
        .err()
        .expect("no camera");
    assert!(e.contains("no camera"), "{e}");
}

#[test]
fn a_bare_gltf_renders_with_its_camera_or_a_default_one_and_a_default_background() {
    use lightgraph_scenes::model::{Light, Look};
    for with_camera in [true, false] {
        let dir = scratch(&format!("bare-{with_camera}"));
        let path = write_quad_gltf(&dir, with_camera);
        // Without its emission the asset has no light.
        let json = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, json.replace(r#""emissiveFactor": [0.5, 0.25, 0.0],"#, "")).unwrap();
        let scene = lightgraph::run::load_scene_with(path.to_str().unwrap(), BvhKind::Cwbvh).unwrap();
        assert!(
            matches!(
                scene.scene.lights[..],
                [Light::Background {
                    radiance: [1.0, 1.0, 1.0],
                    ..
                }]
            ),
            "a default background: {:?}",
            scene.scene.lights
        );
        let camera = scene.scene.camera.as_ref().unwrap();
        if with_camera {
            assert!(close(camera.position, [0.0, 0.0, 3.0]));
            assert_eq!(scene.scene.resolution, (1024, 512), "the camera's aspect ratio");
        } else {
            let Look::Target(target) = camera.look else {
                panic!("a target")
            };
            assert!(close(target, [-0.5, 0.5, -2.0]), "the centre of the bounds: {target:?}");
        }
        let r = render(&scene, "pt", "NaivePTsk", (16, 8), 1, 1, 3, &[]);
        assert_eq!(r.counters["samples_rejected"], 0);
        assert_finite(&r.image, "bare glTF");
        assert!(r.image.mean.iter().any(|p| p[0] > 0.0), "the background shows");
    }
}
