//! The built-in scenes: they load, render without NaN, infinite or negative samples, and
//! the Rust mirrors of the scene structs match the WGSL layouts naga computes.

use crate::assets::NOT_IN_SHARED_COPY;
use crate::common::{assert_finite, gpu, render, shared_assets};
use lightgraph::assets::scene_names;
use lightgraph::run::load_scene;
use lightgraph_engine::reflect::struct_layout;
use lightgraph_engine::wgsl::preprocess;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::gpu::{
    self, GpuAliasEntry, GpuBvhNode, GpuCamera, GpuCwbvhNode, GpuEnvironment, GpuLight, GpuMaterial, GpuPrimitive,
    GpuSceneInfo, GpuTextureInfo, GpuTriangleAttributes,
};
use std::collections::BTreeSet;
use std::mem::{offset_of, size_of};

/// The built-in scenes but the stress scenes (which have their own invariants,
/// tests/integration/stress.rs: one is black), each with the asset files it reads.
fn builtin_scenes() -> Vec<(String, Vec<String>)> {
    let names = scene_names();
    assert!(names.len() >= 6, "the six Cornell scenes are built in: {names:?}");
    names
        .into_iter()
        .filter(|(_, p)| !p.starts_with("scenes/stress/"))
        .map(|(name, path)| {
            let text = lightgraph::assets::builtin().read(&path).unwrap();
            let spec = lightgraph_scenes::parse_scene(&path, &text).unwrap();
            (name, lightgraph::assets::scene_asset_files(&spec))
        })
        .collect()
}

#[test]
fn every_builtin_scene_without_assets_renders_without_invalid_samples() {
    let _ = gpu();
    let scenes = builtin_scenes();
    let without: Vec<&String> = scenes.iter().filter(|(_, f)| f.is_empty()).map(|(n, _)| n).collect();
    assert!(without.len() >= 6, "{without:?}");
    for name in without {
        renders_without_invalid_samples(name);
    }
}

/// Whether a scene over `files` needs an asset the shared copy holds only in part (see
/// [`NOT_IN_SHARED_COPY`]).
fn needs_fetched_files(files: &[String]) -> bool {
    let asset = NOT_IN_SHARED_COPY.split('/').next().expect("an asset folder");
    files.iter().any(|f| f.split('/').next() == Some(asset))
}

#[test]
#[ignore = "needs the shared assets (every built-in scene's): cargo xtask test --assets"]
fn every_builtin_scene_over_the_shared_assets_renders_without_invalid_samples() {
    every_builtin_scene_over_assets_renders(false);
}

#[test]
#[ignore = "needs LivingRoom's Mitsuba meshes, which the shared copy lacks: lightgraph assets fetch LivingRoom --to ROOT, then cargo test --release --test integration -- --ignored fetched_assets"]
fn every_builtin_scene_over_the_fetched_assets_renders_without_invalid_samples() {
    every_builtin_scene_over_assets_renders(true);
}

/// Renders every built-in scene over assets (those needing files the shared copy lacks, or
/// the others) after checking their assets are under the asset root.
fn every_builtin_scene_over_assets_renders(fetched: bool) {
    let _ = gpu();
    let scenes: Vec<(String, Vec<String>)> = builtin_scenes()
        .into_iter()
        .filter(|(_, f)| !f.is_empty() && needs_fetched_files(f) == fetched)
        .collect();
    assert!(!scenes.is_empty(), "no built-in scene over such assets");
    let mut assets: Vec<&str> = scenes
        .iter()
        .flat_map(|(_, files)| files.iter().map(|f| f.split('/').next().unwrap()))
        .collect();
    assets.sort();
    assets.dedup();
    shared_assets(&assets);
    for (name, _) in &scenes {
        renders_without_invalid_samples(name);
    }
}

/// Renders the built-in scene `name` with both naive path-tracing layouts and checks that no
/// NaN, infinite or negative sample reached the film, one primary ray per path, and light.
fn renders_without_invalid_samples(name: &str) {
    let scene = load_scene(name).unwrap();
    for layout in ["NaivePTsk", "NaivePTmk"] {
        let r = render(&scene, "pt", layout, (32, 32), 2, 2, 7, &[]);
        let rejected = r.counters["samples_rejected"];
        eprintln!(
            "{name} {layout}: {} rays, {rejected} rejected samples",
            r.counters["rays_primary"] + r.counters["rays_extension"] + r.counters["rays_shadow"]
        );
        assert_eq!(
            rejected, 0,
            "{name} ({layout}): NaN, infinite or negative samples reached the film"
        );
        assert_eq!(r.loops_capped, 0, "{name}: a path loop hit the iteration cap");
        assert_eq!(
            r.counters["rays_primary"],
            32 * 32 * 2 * 2,
            "{name}: one primary ray per path"
        );
        assert_finite(&r.image, name);
        assert!(
            r.image.mean.iter().any(|p| p.iter().any(|&v| v > 0.0)),
            "{name}: the image is black"
        );
    }
}

/// Checks both variants of scene.wgsl: the BVH2 one, and the CWBVH one (`CwbvhNode` is then the
/// compressed wide node's fields, `BvhNode` the same bytes as the buffer holds them). Primitives
/// likewise: `PrimitiveFields` against the Rust struct, `Primitive` (the buffer's words) its size.
#[test]
fn rust_scene_structs_match_the_wgsl_layout() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/lib/scene.wgsl")).unwrap();
    for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
        let flags: BTreeSet<String> = kind.flag().into_iter().map(String::from).collect();
        let source = preprocess("shaders/lib/scene.wgsl", &text, &flags).unwrap();
        check_scene_structs(&naga::front::wgsl::parse_str(&source).unwrap(), kind);
    }
}

/// The flags and kinds the host writes into scene buffers have the values scene.wgsl tests for.
#[test]
fn rust_scene_constants_match_the_wgsl_constants() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/lib/scene.wgsl")).unwrap();
    let flags = BTreeSet::from(["NORMAL_MAPS".to_string()]);
    let source = preprocess("shaders/lib/scene.wgsl", &text, &flags).unwrap();
    let module = naga::front::wgsl::parse_str(&source).unwrap();
    let wgsl = |name: &str| -> u32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("scene.wgsl has no constant {name}"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref e => panic!("{name} is not a u32 literal: {e:?}"),
        }
    };
    for (name, rust) in [
        ("PRIMITIVE_TRIANGLE", gpu::primitive_kind::TRIANGLE),
        ("PRIMITIVE_SPHERE", gpu::primitive_kind::SPHERE),
        ("PRIMITIVE_ALPHA_MASKED", gpu::primitive_kind::ALPHA_MASKED),
        ("MATERIAL_TWO_SIDED", gpu::material_flags::TWO_SIDED),
        ("MATERIAL_PBR", gpu::material_flags::PBR),
        ("MATERIAL_ALPHA_MASK", gpu::material_flags::ALPHA_MASK),
        ("MATERIAL_THIN_WALLED", gpu::material_flags::THIN_WALLED),
        ("LIGHT_AREA", gpu::light_kind::AREA),
        ("LIGHT_POINT", gpu::light_kind::POINT),
        ("LIGHT_DIRECTIONAL", gpu::light_kind::DIRECTIONAL),
        ("LIGHT_BACKGROUND", gpu::light_kind::BACKGROUND),
        ("LIGHT_SPOT", gpu::light_kind::SPOT),
        ("LIGHT_ENVIRONMENT", gpu::light_kind::ENVIRONMENT),
        ("ATTRIBUTE_NORMALS", gpu::attribute_flags::NORMALS),
        ("ATTRIBUTE_TANGENTS", gpu::attribute_flags::TANGENTS),
        ("ATTRIBUTE_TANGENTS_SHIFT", gpu::attribute_flags::TANGENTS_SHIFT),
    ] {
        assert_eq!(wgsl(name), rust, "{name}");
    }
}

fn check_scene_structs(module: &naga::Module, kind: BvhKind) {
    macro_rules! check {
        ($wgsl:literal, $rust:ty, [$($field:ident),*]) => {{
            let (size, members) = struct_layout(module, $wgsl).expect($wgsl);
            assert_eq!(size as usize, size_of::<$rust>(), "size of {}", $wgsl);
            let rust: Vec<(String, usize)> = vec![$((stringify!($field).to_string(), offset_of!($rust, $field))),*];
            let wgsl: Vec<(String, usize)> = members.into_iter().map(|(n, o)| (n, o as usize)).collect();
            assert_eq!(rust, wgsl, "fields of {}", $wgsl);
        }};
    }
    check!(
        "SceneInfo",
        GpuSceneInfo,
        [center, radius, num_lights, background, num_primitives, num_materials]
    );
    check!(
        "Camera",
        GpuCamera,
        [position, width, forward, height, right, lens_radius, up, focus_distance]
    );
    check!("PrimitiveFields", GpuPrimitive, [a, material, b, light, c, kind]);
    let (size, _) = struct_layout(module, "Primitive").expect("Primitive");
    assert_eq!(size as usize, size_of::<GpuPrimitive>(), "size of Primitive");
    match kind {
        BvhKind::Bvh2 => check!(
            "BvhNode",
            GpuBvhNode,
            [
                left_min,
                left_first,
                left_max,
                left_count,
                right_min,
                right_first,
                right_max,
                right_count
            ]
        ),
        BvhKind::Cwbvh => {
            let (size, _) = struct_layout(module, "BvhNode").expect("BvhNode");
            assert_eq!(size as usize, size_of::<GpuCwbvhNode>(), "size of the CWBVH's BvhNode");
            check!(
                "CwbvhNode",
                GpuCwbvhNode,
                [
                    p,
                    e_imask,
                    child_base,
                    primitive_base,
                    child_meta,
                    child_min_x,
                    child_max_x,
                    child_min_y,
                    child_max_y,
                    child_min_z,
                    child_max_z
                ]
            )
        }
    }
    check!(
        "Material",
        GpuMaterial,
        [
            diffuse,
            phong_exponent,
            phong,
            ior,
            mirror,
            flags,
            emission,
            metallic,
            roughness,
            transmission,
            alpha,
            alpha_cutoff,
            base_color_texture,
            metallic_roughness_texture,
            emissive_texture,
            normal_texture
        ]
    );
    check!(
        "TextureInfo",
        GpuTextureInfo,
        [row0, offset, row1, flags, width, height, pad]
    );
    check!(
        "TriangleAttributes",
        GpuTriangleAttributes,
        [uv0, uv1, uv2, n0, n1, n2, flags]
    );
    check!(
        "Light",
        GpuLight,
        [
            position, kind, e1, inv_area, e2, cos_inner, normal, cos_outer, radiance, pad2
        ]
    );
    check!("AliasEntry", GpuAliasEntry, [keep, other, pmf]);
    check!(
        "Environment",
        GpuEnvironment,
        [width, height, cos_rotation, sin_rotation, pole_to_pole]
    );
}
