//! glTF normal maps. The tilted square of `shading.rs` as a glTF asset: a flat diffuse square
//! whose normal map encodes a constant tilt of 30 degrees, rendered by every estimator with
//! the tangents of the file and with MikkTSpace's; the map's scale; what the importer makes of
//! tangents (given, generated, mirrored) and of a missing or broken image.
//!
//! The square's texture coordinates are turned 45 degrees against its edges, so that the
//! tangent (along u) and the bitangent (up the image) both lie across the light's plane: a
//! wrong sign of either, a wrong handedness, or an sRGB decode of the map changes the radiance.

use crate::common::{region, render};
use crate::shading::{check_tilted_square, on_square};
use lightgraph::run::LoadedScene;
use lightgraph_engine::ConstValue;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::model::Shape;
use std::path::{Path, PathBuf};

/// The normal map's texel: the tangent-space normal (sin 30 / sqrt 2, sin 30 / sqrt 2, cos 30)
/// (30 degrees from the normal, towards the tangent plus the bitangent, which is world +x) as
/// 2 texel - 1 in 8 bits.
const TEXEL: [u8; 3] = [173, 173, 238];

/// The square's unit tangent (along u) at every vertex, with handedness +1: the bitangent
/// normal x tangent = (1, 0, 1) / sqrt 2 points up the image (v down, glTF's).
const TANGENT: [f32; 4] = [
    std::f32::consts::FRAC_1_SQRT_2,
    0.0,
    -std::f32::consts::FRAC_1_SQRT_2,
    1.0,
];

/// What the square's glTF holds.
struct Square {
    /// The file gives TANGENT (else the importer generates them).
    tangents: bool,
    /// The normal texture's scale.
    scale: f32,
    /// The node mirrors x.
    mirrored: bool,
    /// The normal map image's file.
    image: Image,
}

enum Image {
    Png,
    Missing,
    Corrupt,
}

impl Square {
    fn given() -> Square {
        Square {
            tangents: true,
            scale: 1.0,
            mirrored: false,
            image: Image::Png,
        }
    }

    fn generated() -> Square {
        Square {
            tangents: false,
            ..Square::given()
        }
    }
}

/// A folder of its own for `test`'s files.
fn folder(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-normal-maps-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `square.gltf` (the square [-1, 1]^2 at y = 0 facing -y, a diffuse base colour 0.8
/// with no specular layer) with its buffer and normal map into `dir`; returns its path.
fn write_square(dir: &Path, square: &Square) -> PathBuf {
    let positions: [[f32; 3]; 4] = [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]];
    // u increases along (1, 0, -1), glTF's v (down the image) along -(1, 0, 1).
    let uvs = positions.map(|[x, _, z]| [(x - z + 2.0) / 4.0, (2.0 - x - z) / 4.0]);
    let normals = [[0.0f32, -1.0, 0.0]; 4];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = Vec::new();
    bin.extend_from_slice(bytemuck::cast_slice(&positions));
    bin.extend_from_slice(bytemuck::cast_slice(&normals));
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    bin.extend_from_slice(bytemuck::cast_slice(&[TANGENT; 4]));
    bin.extend_from_slice(bytemuck::cast_slice(&indices));
    std::fs::write(dir.join("square.bin"), &bin).unwrap();
    let png = dir.join("tilt.png");
    match square.image {
        Image::Png => image::RgbImage::from_pixel(2, 2, image::Rgb(TEXEL)).save(&png).unwrap(),
        Image::Missing => {}
        Image::Corrupt => std::fs::write(&png, b"\x89PNG\r\n\x1a\nnot an image").unwrap(),
    }
    let tangent = if square.tangents { r#", "TANGENT": 3"# } else { "" };
    let mirror = if square.mirrored {
        r#", "scale": [-1, 1, 1]"#
    } else {
        ""
    };
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_materials_specular"],
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"name": "square", "mesh": 0{mirror}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2{tangent}}}, "indices": 4, "material": 0}}]}}],
  "materials": [{{
    "name": "plate",
    "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
    "normalTexture": {{"index": 0, "scale": {scale}}},
    "extensions": {{"KHR_materials_specular": {{"specularFactor": 0}}}}
  }}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "tilt.png"}}],
  "buffers": [{{"uri": "square.bin", "byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 128, "byteLength": 64}},
    {{"buffer": 0, "byteOffset": 192, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC4"}},
    {{"bufferView": 4, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        scale = square.scale,
        len = bin.len()
    );
    let path = dir.join("square.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// The tilted square's scene (camera and directional light of
/// tests/data/scenes/tilted-normals-quad.ron) around the glTF `square`.
fn square_scene(test: &str, square: &Square) -> LoadedScene {
    let dir = folder(test);
    write_square(&dir, square);
    let text = r#"Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    resolution: (32, 32),
    gltf: "square.gltf",
    lights: [Directional(direction: (0.70710678, 0.70710678, 0.0), irradiance: (3.14159265, 6.2831853, 1.57079633))],
)"#;
    let scene = LoadedScene::parse(test, text, BvhKind::Bvh2, Some(&dir)).unwrap();
    std::fs::remove_dir_all(dir).unwrap();
    scene
}

/// The square's radiance with a map of scale `scale`: albedo / pi * E * (l . ns) with
/// ns = normalize(t x s + b y s + n z) for the texel's (x, y, z) = 2 texel / 255 - 1 (as
/// stored: 8 bits, linear), t = (1, 0, -1) / sqrt 2, b = (1, 0, 1) / sqrt 2, n = (0, -1, 0),
/// l = (-1, -1, 0) / sqrt 2 and E = (pi, 2 pi, pi / 2). Mirrored in x, t and b are too.
fn mapped_radiance(scale: f64, mirrored: bool) -> [f64; 3] {
    let [x, y, z] = TEXEL.map(|c| 2.0 * c as f64 / 255.0 - 1.0);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let mirror = if mirrored { -1.0 } else { 1.0 };
    let ns = [mirror * h * (x + y) * scale, -z, h * (y - x) * scale];
    let length = ns.iter().map(|c| c * c).sum::<f64>().sqrt();
    let cosine = h * (-ns[0] - ns[1]) / length;
    [1.0, 2.0, 0.5].map(|e| 0.8 * cosine * e)
}

#[test]
fn a_normal_mapped_square_has_the_tilted_planes_radiance_in_every_estimator() {
    let expected = mapped_radiance(1.0, false);
    // The map tilts the normal 30 degrees as the vertex normals of shading.rs do, within the
    // texels' rounding (30.2 degrees: 1.4% less radiance).
    let [x, y, z] = TEXEL.map(|c| 2.0 * c as f64 / 255.0 - 1.0);
    let tilt = (x.hypot(y) / z).atan().to_degrees();
    assert!((tilt - 30.0).abs() < 0.25, "{tilt} degrees");
    // Tolerances as shading.rs's (4 standard errors, float rounding for PT, whose only noise
    // is the jitter over a constant radiance): 14 renders of 3 channels here, a false failure
    // about once in 380 runs. The map is constant, so its filtering adds nothing.

    check_tilted_square(&square_scene("given", &Square::given()), "given tangents", expected);
    check_tilted_square(
        &square_scene("generated", &Square::generated()),
        "MikkTSpace tangents",
        expected,
    );
}

#[test]
fn the_maps_scale_and_a_mirrored_frame_change_the_tilt() {
    // Scale 0.5 halves the map's x and y: a tilt of 16 rather than 30 degrees, 1.9 times the
    // radiance. Mirrored in x (handedness -1 on the GPU), the normal tilts towards -x, away
    // from the tilted plane of the light: 3.7 times the radiance. In path and light tracing
    // (the adjoint BSDF's correction of the mapped normal).
    let scale = Square {
        scale: 0.5,
        ..Square::given()
    };
    let mirrored = Square {
        mirrored: true,
        ..Square::given()
    };
    assert!(mapped_radiance(0.5, false)[0] > 1.8 * mapped_radiance(1.0, false)[0]);
    assert!(mapped_radiance(1.0, true)[0] > 3.6 * mapped_radiance(1.0, false)[0]);
    for (what, square, expected) in [
        ("scale 0.5", scale, mapped_radiance(0.5, false)),
        ("mirrored", mirrored, mapped_radiance(1.0, true)),
    ] {
        let scene = square_scene(&what.replace(" ", "-"), &square);
        for (graph, layout, frames) in [("pt", "NaivePTsk", 4), ("lt", "LTsk", 16)] {
            let r = render(
                &scene,
                graph,
                layout,
                (32, 32),
                4,
                frames,
                5,
                &[] as &[(&str, ConstValue)],
            );
            let (mean, se, _) = region(&r.image, on_square(32, 0.1));
            crate::common::assert_analytic(&format!("{graph}, {what}"), mean, se, expected, 4.0, 1e-4);
        }
    }
}

/// The one mesh of `square` as imported, with its tangents.
fn imported_tangents(test: &str, square: &Square) -> Vec<[[f32; 4]; 3]> {
    let dir = folder(test);
    let imported = lightgraph_scenes::gltf::import(&write_square(&dir, square));
    std::fs::remove_dir_all(dir).unwrap();
    match &imported.unwrap().shapes[..] {
        [Shape::Mesh { tangents: Some(t), .. }] => t.clone(),
        shapes => panic!("one mesh with tangents: {shapes:?}"),
    }
}

fn assert_every_corner(tangents: &[[[f32; 4]; 3]], expected: [f32; 4], what: &str) {
    for t in tangents.iter().flatten() {
        let off: f32 = t.iter().zip(expected).map(|(a, b)| (a - b).abs()).sum();
        assert!(off < 1e-5, "{what}: {t:?}, expected {expected:?}");
    }
}

#[test]
fn tangents_are_the_files_or_mikktspaces_and_a_mirror_flips_their_handedness() {
    assert_every_corner(&imported_tangents("import-given", &Square::given()), TANGENT, "given");
    // MikkTSpace in the image's orientation finds the file's frame: the bitangent up the
    // image (glTF's v runs down it).
    let generated = imported_tangents("import-generated", &Square::generated());
    assert_every_corner(&generated, TANGENT, "generated");
    // Mirrored in x: the tangent turns with the mesh, and so must the bitangent, which
    // normal x tangent alone would not: the handedness flips.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for square in [Square::given(), Square::generated()] {
        let mirrored = Square {
            mirrored: true,
            ..square
        };
        let tangents = imported_tangents("import-mirrored", &mirrored);
        assert_every_corner(&tangents, [-h, 0.0, -h, -1.0], "mirrored");
    }
}

#[test]
fn a_missing_or_broken_normal_map_is_an_error_naming_its_file() {
    for (image, problem) in [(Image::Missing, "No such file"), (Image::Corrupt, "")] {
        let dir = folder("bad-image");
        let path = write_square(
            &dir,
            &Square {
                image,
                ..Square::given()
            },
        );
        let e = lightgraph_scenes::gltf::import(&path).map(|_| ()).unwrap_err();
        std::fs::remove_dir_all(dir).unwrap();
        assert!(
            e.starts_with(&format!("{}: image 0 ('tilt.png'): ", path.display())) && e.contains(problem),
            "{e}"
        );
    }
}
