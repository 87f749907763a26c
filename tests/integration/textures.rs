//! Textures, vertex attributes and alpha masks on the GPU: bilinear lookups (sRGB decode,
//! wrap modes, KHR_texture_transform) against a CPU evaluation in f64; interpolated texture
//! coordinates and shading normals at ray hits; alpha-masked triangles that rays pass through
//! where alpha is below the cutoff, in closest-hit and any-hit traversal of both BVH kinds, in
//! a test graph, in path tracing (an emitter seen through the holes) and in ambient occlusion.

use crate::common::{data, gpu, render};
use lightgraph::run::LoadedScene;
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, compile};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::gpu::{GpuTextureInfo, texture_flags};
use lightgraph_scenes::model::{Camera, FovAxis, Integrator, Light, Look, Material, Pbr, Scene, Shape};
use lightgraph_scenes::texture::{PbrTextures, Texture, TextureRef, Wrap};
use std::collections::BTreeMap;

/// A scene of the given materials, shapes, lights and textures, seen from `camera`.
fn scene(
    materials: Vec<(&str, Material)>,
    shapes: Vec<Shape>,
    lights: Vec<Light>,
    textures: Vec<Texture>,
    camera: Camera,
) -> Scene {
    Scene {
        description: "texture test".into(),
        camera: Some(camera),
        gltf_camera: None,
        resolution: (1, 1),
        materials: materials.into_iter().map(|(k, m)| (k.to_string(), m)).collect(),
        shapes,
        lights,
        integrator: Integrator::default(),
        media: Default::default(),
        camera_medium: None,
        gltf: None,
        gltf_diffuse: false,
        gltf_instances: Vec::new(),
        mitsuba: None,
        textures,
    }
}

fn camera_looking_down(z: f32, fov_degrees: f32) -> Camera {
    Camera {
        position: [0.0, 0.0, z],
        look: Look::Forward([0.0, 0.0, -1.0]),
        up: [0.0, 1.0, 0.0],
        fov_degrees,
        fov_axis: FovAxis::Horizontal,
        lens: None,
    }
}

/// A PBR material of base colour `base`, textured by `textures`, alpha-masked at `cutoff`.
fn pbr(base: [f32; 3], textures: PbrTextures, cutoff: Option<f32>) -> Material {
    Material {
        pbr: Some(Pbr {
            base_color: base,
            alpha_cutoff: cutoff,
            textures,
            ..Pbr::default()
        }),
        ..Material::default()
    }
}

/// The quad x, y in [x0, x1] x [y0, y1] at height z facing +z, with texture coordinates
/// u = (x - x0) / (x1 - x0), v = (y - y0) / (y1 - y0) and the given vertex normals.
fn quad(material: &str, [x0, x1, y0, y1, z]: [f32; 5], normals: Option<Vec<[f32; 3]>>) -> Shape {
    Shape::Mesh {
        positions: vec![[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material: material.into(),
        emission: None,
        uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
        normals,
        tangents: None,
    }
}

/// A 4x1 texture whose alpha is 0, 0, 1, 1: bilinear alpha is (u - 3/8) / (1/4) clamped
/// to [0, 1] with clamped wrapping, so it crosses 0.5 exactly at u = 0.5.
fn alpha_ramp() -> Texture {
    Texture {
        name: "alpha ramp".into(),
        width: 4,
        height: 1,
        texels: vec![0x00ffffff, 0x00ffffff, 0xffffffff, 0xffffffff],
    }
}

fn clamped(texture: u32) -> TextureRef {
    TextureRef {
        wrap: [Wrap::ClampToEdge; 2],
        ..TextureRef::new(texture)
    }
}

/// Linear RGBA of texture `info` at `uv`, evaluated in f64: the transform, texel centres at
/// half-integers, wrap per axis, sRGB decode of the colour, bilinear weights.
fn expected_sample(info: &GpuTextureInfo, texels: &[u32], uv: [f32; 2]) -> [f64; 4] {
    let (u, v) = (uv[0] as f64, uv[1] as f64);
    let row = |r: [f32; 3]| r[0] as f64 * u + r[1] as f64 * v + r[2] as f64;
    let (s, t) = (row(info.row0), row(info.row1));
    let wrap = |i: i64, n: i64, mode: u32| -> i64 {
        match mode {
            texture_flags::WRAP_CLAMP => i.clamp(0, n - 1),
            texture_flags::WRAP_MIRROR => {
                let m = i.rem_euclid(2 * n);
                if m >= n { 2 * n - 1 - m } else { m }
            }
            _ => i.rem_euclid(n),
        }
    };
    let texel = |x: i64, y: i64| -> [f64; 4] {
        let word = texels[info.offset as usize + (y * info.width as i64 + x) as usize];
        let c = [0, 8, 16, 24].map(|shift| ((word >> shift) & 0xff) as f64 / 255.0);
        let decode = |c: f64| {
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        };
        if info.flags & texture_flags::SRGB != 0 {
            [decode(c[0]), decode(c[1]), decode(c[2]), c[3]]
        } else {
            c
        }
    };
    let (w, h) = (info.width as i64, info.height as i64);
    let (px, py) = (s * w as f64 - 0.5, t * h as f64 - 0.5);
    let (fx, fy) = (px - px.floor(), py - py.floor());
    let (ix, iy) = (px.floor() as i64, py.floor() as i64);
    let mode_s = (info.flags >> texture_flags::WRAP_S_SHIFT) & 3;
    let mode_t = (info.flags >> texture_flags::WRAP_T_SHIFT) & 3;
    let mut out = [0.0; 4];
    for (dx, dy, weight) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let c = texel(wrap(ix + dx, w, mode_s), wrap(iy + dy, h, mode_t));
        for k in 0..4 {
            out[k] += weight * c[k];
        }
    }
    out
}

/// Runs the surface_query test graph: per query a texture lookup (texture index, uv; a
/// negative index for none) and a ray (origin, direction, any-hit distance).
fn surface_queries(
    compiled: &CompiledScene,
    scene: &Scene,
    queries: &[([f32; 3], [f32; 3], [f32; 4])],
) -> Vec<[f32; 4]> {
    let vfs = lightgraph::assets::builtin().with_front(Layer::Dir(data("")));
    let graph = Graph::load(&vfs, "graphs/surface_query.ron").unwrap();
    let spec = Specialization {
        constants: [("QUERIES".to_string(), ConstValue::U32(queries.len() as u32))]
            .into_iter()
            .collect(),
        flags: compiled
            .bvh_kind
            .flag()
            .map(String::from)
            .into_iter()
            .chain(lightgraph_scenes::features::used(compiled))
            .collect(),
    };
    let program = compile(&graph, "fused", &graph.layouts["fused"], &spec, &gpu().target()).unwrap();
    let mut externals: BTreeMap<String, Vec<u8>> = compiled
        .resources(&CompiledScene::camera(scene, 1, 1))
        .into_iter()
        .filter(|(k, _)| graph.resource_id(k).is_some())
        .collect();
    let words: Vec<[f32; 4]> = queries
        .iter()
        .flat_map(|(tex, o, d)| [[tex[0], tex[1], tex[2], 0.0], [o[0], o[1], o[2], 0.0], *d])
        .collect();
    externals.insert("queries".into(), bytemuck::cast_slice(&words).to_vec());
    let mut instance = Instance::new(gpu(), program, &externals).unwrap();
    instance.run_frame(0, 0).unwrap();
    bytemuck::pod_collect_to_vec(&instance.read("results").unwrap())
}

/// A ray that hits nothing in the query scene.
const MISS: ([f32; 3], [f32; 4]) = ([0.0, 0.0, 10.0], [0.0, 0.0, 1.0, 1.0]);

#[test]
fn texture_lookups_match_a_cpu_evaluation() {
    // A 3x2 image of arbitrary bytes, alpha included.
    let pattern: Vec<u32> = (0..6u32)
        .map(|i| (i * 0x9E3779B9).rotate_left(7) ^ 0x5a5a5a5a)
        .collect();
    let image = Texture {
        name: "pattern".into(),
        width: 3,
        height: 2,
        texels: pattern,
    };
    let (sin, cos) = 0.5f32.sin_cos();
    let transformed = TextureRef {
        wrap: [Wrap::MirroredRepeat, Wrap::Repeat],
        transform: [[cos * 1.5, sin * 0.7, 0.2], [-sin * 1.5, cos * 0.7, -0.3]],
        ..TextureRef::new(0)
    };
    let textures = PbrTextures {
        base_color: Some(TextureRef {
            wrap: [Wrap::Repeat, Wrap::ClampToEdge],
            ..TextureRef::new(0)
        }),
        metallic_roughness: Some(transformed),
        emissive: Some(TextureRef {
            wrap: [Wrap::ClampToEdge, Wrap::MirroredRepeat],
            ..TextureRef::new(0)
        }),
        normal: None,
    };
    let s = scene(
        vec![("m", pbr([1.0; 3], textures, None))],
        vec![quad("m", [-1.0, 1.0, -1.0, 1.0, 0.0], None)],
        vec![],
        vec![image],
        camera_looking_down(1.0, 40.0),
    );
    let compiled = CompiledScene::new(&s).unwrap();
    // Base colour and emission sRGB-decoded, metallic-roughness linear.
    let srgb: Vec<bool> = compiled
        .textures
        .iter()
        .map(|t| t.flags & texture_flags::SRGB != 0)
        .collect();
    assert_eq!(srgb, vec![true, false, true]);
    let coordinates = [-1.3f32, -0.2, 0.0, 0.1, 0.37, 0.5, 0.77, 1.0, 1.6, 2.45];
    let mut queries = Vec::new();
    for t in 0..compiled.textures.len() {
        for &u in &coordinates {
            for &v in &coordinates {
                queries.push(([t as f32, u, v], MISS.0, MISS.1));
            }
        }
    }
    let results = surface_queries(&compiled, &s, &queries);
    // f32 against f64: the texel values are exact bytes, so the difference is the rounding of
    // the transform, the weights and sRGB's pow, below 1e-5; 1e-4 leaves room.
    for (i, (tex, _, _)) in queries.iter().enumerate() {
        let info = &compiled.textures[tex[0] as usize];
        let want = expected_sample(info, &compiled.texels, [tex[1], tex[2]]);
        let got = results[4 * i];
        for k in 0..4 {
            assert!(
                (got[k] as f64 - want[k]).abs() < 1e-4,
                "texture {} at uv ({}, {}): GPU {got:?}, CPU {want:?}",
                tex[0],
                tex[1],
                tex[2]
            );
        }
    }
}

/// A quad whose material's base colour is `r` (an image of `image`), and its compiled scene.
fn textured_quad(image: Texture, r: TextureRef) -> (Scene, CompiledScene) {
    let textures = PbrTextures {
        base_color: Some(r),
        ..Default::default()
    };
    let s = scene(
        vec![("m", pbr([1.0; 3], textures, None))],
        vec![quad("m", [-1.0, 1.0, -1.0, 1.0, 0.0], None)],
        vec![],
        vec![image],
        camera_looking_down(1.0, 40.0),
    );
    let compiled = CompiledScene::new(&s).unwrap();
    (s, compiled)
}

/// Nearest lookups of texture 0 at 200 points (u, v) spread over [-2, 2)^2, but for those
/// whose texel coordinates `texel(u, v)` lie within 1e-3 of a texel edge: the GPU's results
/// against `want(x, y)` of the texel coordinates, which must agree within `tolerance`.
fn check_nearest_lookups(
    s: &Scene,
    compiled: &CompiledScene,
    texel: impl Fn(f32, f32) -> (f32, f32),
    want: impl Fn(f32, f32) -> [f32; 4],
    tolerance: f32,
) {
    let mut queries = Vec::new();
    let mut wanted = Vec::new();
    for i in 0..200u32 {
        let (u, v) = (
            (i as f32 * 0.618_034).fract() * 4.0 - 2.0,
            (i as f32 * 0.754_878).fract() * 4.0 - 2.0,
        );
        let (x, y) = texel(u, v);
        if (x - x.round()).abs() < 1e-3 || (y - y.round()).abs() < 1e-3 {
            continue;
        }
        wanted.push(want(x, y));
        queries.push(([0.0, u, v], MISS.0, MISS.1));
    }
    assert!(wanted.len() > 150);
    let results = surface_queries(compiled, s, &queries);
    for (i, want) in wanted.iter().enumerate() {
        let got = results[4 * i];
        for k in 0..4 {
            assert!(
                (got[k] - want[k]).abs() <= tolerance,
                "uv ({}, {}): GPU {got:?}, texel {want:?}",
                queries[i].0[1],
                queries[i].0[2]
            );
        }
    }
}

#[test]
fn nearest_lookups_return_the_texel_under_the_point() {
    // A 3x2 image of arbitrary bytes, read as linear even in the sRGB base colour slot.
    let pattern: Vec<u32> = (0..6u32)
        .map(|i| (i * 0x9E3779B9).rotate_left(11) ^ 0x3c3c3c3c)
        .collect();
    let image = Texture {
        name: "pattern".into(),
        width: 3,
        height: 2,
        texels: pattern.clone(),
    };
    let nearest = TextureRef {
        wrap: [Wrap::Repeat, Wrap::MirroredRepeat],
        transform: [[2.0, 0.5, 0.1], [-0.5, 3.0, 0.2]],
        nearest: true,
        linear: true,
        ..TextureRef::new(0)
    };
    let (s, compiled) = textured_quad(image, nearest);
    assert_eq!(
        compiled.textures[0].flags & (texture_flags::SRGB | texture_flags::NEAREST),
        texture_flags::NEAREST
    );
    // (s, t) = transform (u, v) in cells of 1/3 x 1/2.
    let texel = |u: f32, v: f32| ((2.0 * u + 0.5 * v + 0.1) * 3.0, (-0.5 * u + 3.0 * v + 0.2) * 2.0);
    let want = |x: f32, y: f32| {
        let column = (x.floor() as i64).rem_euclid(3);
        let row = (y.floor() as i64).rem_euclid(4);
        let row = if row >= 2 { 3 - row } else { row };
        let word = pattern[(row * 3 + column) as usize];
        [0, 8, 16, 24].map(|shift| ((word >> shift) & 0xff) as f32 / 255.0)
    };
    check_nearest_lookups(&s, &compiled, texel, want, 1e-6);
}

#[test]
fn a_checkerboard_returns_its_colours_at_full_precision() {
    // Colours that 8 bits round (0.1 is stored as 26/255 = 0.10196): the GPU must return the
    // file's values, not its image's texels.
    let colors = [[0.1, 0.3, 0.7], [0.8, 0.2, 0.21]];
    let bytes = colors.map(|c| {
        let [r, g, b] = c.map(|v: f32| (v * 255.0).round() as u32);
        r | g << 8 | b << 16 | 0xff << 24
    });
    let image = Texture {
        name: "checker".into(),
        width: 2,
        height: 2,
        texels: vec![bytes[0], bytes[1], bytes[1], bytes[0]],
    };
    let checker = TextureRef {
        transform: [[3.0, 0.0, 0.25], [0.0, 5.0, -0.1]],
        nearest: true,
        linear: true,
        checker: Some(colors),
        ..TextureRef::new(0)
    };
    let (s, compiled) = textured_quad(image, checker);
    assert_ne!(compiled.textures[0].flags & texture_flags::CHECKER, 0);
    let texel = |u: f32, v: f32| ((3.0 * u + 0.25) * 2.0, (5.0 * v - 0.1) * 2.0);
    let want = |x: f32, y: f32| {
        let c = colors[(x.floor() as i64 + y.floor() as i64).rem_euclid(2) as usize];
        [c[0], c[1], c[2], 1.0]
    };
    // Exactly the file's values.
    check_nearest_lookups(&s, &compiled, texel, want, 0.0);
}

#[test]
fn alpha_masks_let_rays_through_in_both_bvhs_and_surfaces_interpolate_attributes() {
    // The quad "a" below, with normals leaning outwards at its corners; the alpha-masked quad
    // above it over y < 0, whose alpha crosses the cutoff 0.5 at x = 0.
    let lean = |x: f32, y: f32| {
        let n = [0.3 * x, 0.3 * y, 1.0];
        let l = (n[0] * n[0] + n[1] * n[1] + 1.0f32).sqrt();
        n.map(|c| c / l)
    };
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let normals: Vec<[f32; 3]> = corners.iter().map(|&(x, y)| lean(x, y)).collect();
    let mask = PbrTextures {
        base_color: Some(clamped(0)),
        ..PbrTextures::default()
    };
    let s = scene(
        vec![
            ("a", pbr([0.5; 3], PbrTextures::default(), None)),
            ("mask", pbr([0.5; 3], mask, Some(0.5))),
        ],
        vec![
            quad("a", [-1.0, 1.0, -1.0, 1.0, 0.0], Some(normals.clone())),
            quad("mask", [-1.0, 1.0, -1.0, 0.0, 0.5], None),
        ],
        vec![],
        vec![alpha_ramp()],
        camera_looking_down(1.0, 40.0),
    );
    let down = [0.0, 0.0, -1.0, 10.0];
    let mut queries = Vec::new();
    let mut expect = Vec::new();
    // Over the mask: rays meet the mask where x >= 0 (alpha >= 0.5), else the quad below.
    for x in [-0.9f32, -0.6, -0.3, -0.1, 0.1, 0.3, 0.6, 0.9] {
        queries.push(([-1.0, 0.0, 0.0], [x, -0.5, 1.0], down));
        expect.push(if x >= 0.0 { 0.5 } else { 1.0 });
    }
    // Beside the mask: the quad below, at points of both triangles.
    let points = [(-0.7f32, 0.2f32), (0.4, 0.9), (0.8, 0.3), (-0.2, 0.6)];
    for &(x, y) in &points {
        queries.push(([-1.0, 0.0, 0.0], [x, y, 1.0], down));
        expect.push(1.0);
    }
    // Any-hit limited to 0.75: only the mask's solid half lies that close.
    queries.push(([-1.0, 0.0, 0.0], [-0.5, -0.5, 1.0], [0.0, 0.0, -1.0, 0.75]));
    expect.push(1.0);
    queries.push(([-1.0, 0.0, 0.0], [0.5, -0.5, 1.0], [0.0, 0.0, -1.0, 0.75]));
    expect.push(0.5);
    for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
        let compiled = CompiledScene::with_bvh(&s, kind).unwrap();
        let results = surface_queries(&compiled, &s, &queries);
        for (i, (_, o, d)) in queries.iter().enumerate() {
            let hit = results[4 * i + 1];
            let any_expected = if d[3] < 1.0 { o[0] >= 0.0 } else { true };
            assert_eq!(hit[0], 1.0, "{kind:?}: ray at ({}, {}) finds a surface", o[0], o[1]);
            assert!(
                (hit[1] - expect[i]).abs() < 1e-5,
                "{kind:?}: ray at ({}, {}) stops at t = {}, expected {}",
                o[0],
                o[1],
                hit[1],
                expect[i]
            );
            assert_eq!(
                hit[2] == 1.0,
                any_expected,
                "{kind:?}: any hit of the ray at ({}, {})",
                o[0],
                o[1]
            );
        }
        // Texture coordinates and shading normals on the quad below: linear in x, y within
        // each triangle (quad corners in order: triangles (0, 1, 2) and (0, 2, 3)).
        for (j, &(x, y)) in points.iter().enumerate() {
            let i = 8 + j;
            let tex = results[4 * i + 3];
            let (u, v) = ((x + 1.0) / 2.0, (y + 1.0) / 2.0);
            assert!(
                (tex[0] - u).abs() < 1e-5 && (tex[1] - v).abs() < 1e-5,
                "{kind:?}: texture coordinates at ({x}, {y}): {tex:?}"
            );
            // Barycentrics of the triangle holding (u, v).
            let (w, tri) = if u >= v {
                ([1.0 - u, u - v, v], [0, 1, 2])
            } else {
                ([1.0 - v, u, v - u], [0, 2, 3])
            };
            let mut n = [0.0f32; 3];
            for k in 0..3 {
                for c in 0..3 {
                    n[c] += w[k] * normals[tri[k]][c];
                }
            }
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let got = results[4 * i + 2];
            // Octahedral snorm16 normals are exact to about 1e-4.
            for c in 0..3 {
                assert!(
                    (got[c] - n[c] / l).abs() < 1e-3,
                    "{kind:?}: shading normal at ({x}, {y}): {got:?}, expected {:?}",
                    n.map(|v| v / l)
                );
            }
        }
    }
}

/// Path tracing with one segment (emitters seen directly): an emitter behind an alpha-masked
/// quad shows exactly where the mask's alpha is below the cutoff (x < 0), and nothing shows
/// where it is solid.
#[test]
fn an_emitter_shows_through_the_holes_of_an_alpha_mask() {
    let mask = PbrTextures {
        base_color: Some(clamped(0)),
        ..PbrTextures::default()
    };
    let radiance = [2.0, 3.0, 4.0];
    let s = scene(
        vec![("mask", pbr([0.5; 3], mask, Some(0.5))), ("wall", Material::default())],
        vec![
            quad("mask", [-1.0, 1.0, -1.0, 1.0, 0.0], None),
            Shape::Quad {
                corners: [
                    [-3.0, -3.0, -1.0],
                    [3.0, -3.0, -1.0],
                    [3.0, 3.0, -1.0],
                    [-3.0, 3.0, -1.0],
                ],
                material: "wall".into(),
                emission: Some(radiance),
            },
        ],
        vec![],
        vec![alpha_ramp()],
        camera_looking_down(3.0, 30.0),
    );
    let loaded = LoadedScene {
        name: "mask".into(),
        compiled: CompiledScene::with_bvh(&s, BvhKind::Cwbvh).unwrap(),
        scene: s,
        load_seconds: 0.0,
    };
    let (w, h) = (32u32, 8u32);
    let r = render(
        &loaded,
        "pt",
        "NaivePTsk",
        (w, h),
        4,
        1,
        5,
        &[("MAX_PATH_LENGTH", ConstValue::U32(1))],
    );
    for y in 0..h {
        for x in 0..w {
            // The pixel's horizontal extent in normalised coordinates; x = 0 on the mask
            // is the image's centre line. Pixels it crosses are mixed.
            let (left, right) = (x as f32 / w as f32 * 2.0 - 1.0, (x + 1) as f32 / w as f32 * 2.0 - 1.0);
            if left < 1e-3 && right > -1e-3 {
                continue;
            }
            let want = if right <= 0.0 { radiance } else { [0.0; 3] };
            let got = r.image.mean[(y * w + x) as usize];
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() < 1e-5,
                    "pixel ({x}, {y}): {got:?}, expected {want:?}"
                );
            }
        }
    }
}

/// Ambient occlusion under an alpha-masked roof: with alpha 0 below the cutoff 0.5 the roof
/// is all holes and every occlusion ray escapes (exactly 1); with cutoff 0 it is solid and
/// only rays slipping out under its far edges escape (about (h / R)^2 = 2.5e-5 of the
/// cosine-weighted hemisphere for height h = 0.5 and half-width R = 100).
#[test]
fn occlusion_rays_pass_through_alpha_masked_holes() {
    let transparent = Texture {
        name: "transparent".into(),
        width: 1,
        height: 1,
        texels: vec![0x00ffffff],
    };
    for (cutoff, range) in [(0.5, 1.0..=1.0), (0.0, 0.0..=0.01)] {
        let roof = PbrTextures {
            base_color: Some(TextureRef::new(0)),
            ..PbrTextures::default()
        };
        let s = scene(
            vec![
                ("roof", pbr([0.5; 3], roof, Some(cutoff))),
                ("floor", pbr([0.5; 3], PbrTextures::default(), None)),
            ],
            vec![
                quad("roof", [-100.0, 100.0, -100.0, 100.0, 1.0], None),
                quad("floor", [-100.0, 100.0, -100.0, 100.0, 0.0], None),
            ],
            vec![Light::Background {
                radiance: [1.0; 3],
                scale: 1.0,
            }],
            vec![transparent.clone()],
            camera_looking_down(0.5, 60.0),
        );
        let loaded = LoadedScene {
            name: "roof".into(),
            compiled: CompiledScene::with_bvh(&s, BvhKind::Bvh2).unwrap(),
            scene: s,
            load_seconds: 0.0,
        };
        let r = render(&loaded, "ao", "AOsk", (8, 8), 4, 1, 3, &[]);
        let mean = r.image.mean.iter().map(|p| p[0] as f64).sum::<f64>() / 64.0;
        assert!(
            range.contains(&mean),
            "cutoff {cutoff}: occlusion mean {mean}, expected in {range:?}"
        );
    }
}

/// Kernels sample textures and test alpha masks only for scenes that have them.
#[test]
fn only_scenes_with_textures_or_masks_set_their_flags() {
    let cornell = lightgraph::run::load_scene("cornell-diffuse").unwrap();
    let shading = |flags: std::collections::BTreeSet<String>| -> Vec<String> {
        flags
            .into_iter()
            .filter(|f| f == "TEXTURES" || f == "ALPHA_MASK")
            .collect()
    };
    assert!(shading(lightgraph_scenes::features::used(&cornell.compiled)).is_empty());
    let textured = |cutoff| {
        let textures = PbrTextures {
            base_color: Some(TextureRef::new(0)),
            ..PbrTextures::default()
        };
        let s = scene(
            vec![("m", pbr([1.0; 3], textures, cutoff))],
            vec![quad("m", [-1.0, 1.0, -1.0, 1.0, 0.0], None)],
            vec![],
            vec![alpha_ramp()],
            camera_looking_down(1.0, 40.0),
        );
        shading(lightgraph_scenes::features::used(&CompiledScene::new(&s).unwrap()))
    };
    assert_eq!(textured(None), vec!["TEXTURES"]);
    assert_eq!(textured(Some(0.5)), vec!["ALPHA_MASK", "TEXTURES"]);
}
