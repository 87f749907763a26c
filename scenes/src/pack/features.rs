//! The scene features that decide which WGSL code a kernel contains. Each feature is a
//! preprocessor flag of the shaders (`#if LIGHT_POINT` ... `#endif`): a kernel specialised
//! for a scene is generated with the flags of the features the scene uses, so a Cornell box
//! kernel carries no texture, microfacet or environment-map code.

use crate::gpu::{attribute_flags, light_kind, material_flags, primitive_kind};
use crate::pack::compile::CompiledScene;
use std::collections::BTreeSet;

/// Every feature flag, with what it compiles in.
pub const ALL: &[(&str, &str)] = &[
    ("SPHERES", "analytic spheres"),
    ("BSDF_PHONG", "the Phong lobe"),
    (
        "BSDF_SPECULAR",
        "mirrors and smooth dielectrics of the SmallVCM materials",
    ),
    (
        "BSDF_PBR",
        "glTF metallic-roughness: GGX microfacets, rough and smooth transmission",
    ),
    (
        "BSDF_THIN_WALLED",
        "thin-walled transmission of glTF materials: unbent, through a slab",
    ),
    (
        "BSDF_BECKMANN",
        "Beckmann microfacets (Mitsuba's default distribution) beside GGX",
    ),
    (
        "BSDF_ROUGH_PLASTIC",
        "Mitsuba's rough plastic: its coating's tabulated transmittance and internal reflectance",
    ),
    (
        "TEXTURES",
        "texture lookups (base colour, metallic-roughness, emission)",
    ),
    ("ALPHA_MASK", "alpha-masked cut-outs in ray traversal"),
    (
        "SHADING_NORMALS",
        "interpolated vertex normals shading triangles (with the adjoint BSDF's correction)",
    ),
    (
        "NORMAL_MAPS",
        "tangent-space normal maps perturbing the shading normal (with SHADING_NORMALS and TEXTURES)",
    ),
    ("THIN_LENS", "a thin-lens camera: depth of field"),
    ("LIGHT_AREA", "emissive triangles"),
    ("LIGHT_PUNCTUAL", "point or spot lights"),
    ("LIGHT_POINT", "point lights"),
    ("LIGHT_SPOT", "spot lights"),
    ("LIGHT_DIRECTIONAL", "directional lights"),
    (
        "LIGHT_DELTA",
        "point, spot or directional lights: lights no path can hit",
    ),
    ("LIGHT_BACKGROUND", "a constant background"),
    ("LIGHT_ENVIRONMENT", "an environment map"),
    (
        "MEDIA",
        "participating media: free-flight sampling, transmittance, phase functions, index-matched boundaries",
    ),
    (
        "MEDIA_GRID",
        "heterogeneous media (with MEDIA): density grids, delta tracking of free flights, ratio tracking of transmittance",
    ),
];

/// The features `scene` uses, as flag names.
pub fn used(scene: &CompiledScene) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut add = |flag: &str, on: bool| {
        if on {
            out.insert(flag.to_string());
        }
    };
    add(
        "SPHERES",
        scene.primitives.iter().any(|p| p.kind == primitive_kind::SPHERE),
    );
    let vcm = |m: &&crate::gpu::GpuMaterial| m.flags & material_flags::PBR == 0;
    add(
        "BSDF_PHONG",
        scene
            .materials
            .iter()
            .filter(vcm)
            .any(|m| m.phong.iter().any(|&c| c > 0.0)),
    );
    add(
        "BSDF_SPECULAR",
        scene
            .materials
            .iter()
            .filter(vcm)
            .any(|m| m.ior > 0.0 || m.mirror.iter().any(|&c| c > 0.0)),
    );
    add(
        "BSDF_PBR",
        scene.materials.iter().any(|m| m.flags & material_flags::PBR != 0),
    );
    add(
        "BSDF_THIN_WALLED",
        scene
            .materials
            .iter()
            .any(|m| m.flags & material_flags::PBR != 0 && m.flags & material_flags::THIN_WALLED != 0),
    );
    add(
        "BSDF_BECKMANN",
        scene
            .materials
            .iter()
            .any(|m| m.flags & material_flags::PBR != 0 && m.flags & material_flags::BECKMANN != 0),
    );
    let normal_maps = scene
        .attributes
        .iter()
        .any(|a| a.flags & attribute_flags::TANGENTS != 0);
    add("NORMAL_MAPS", normal_maps);
    add(
        "BSDF_ROUGH_PLASTIC",
        scene
            .materials
            .iter()
            .any(|m| m.flags & material_flags::PBR != 0 && m.flags & material_flags::ROUGH_PLASTIC != 0),
    );
    add(
        "TEXTURES",
        normal_maps
            || scene
                .materials
                .iter()
                .any(|m| m.base_color_texture >= 0 || m.metallic_roughness_texture >= 0 || m.emissive_texture >= 0),
    );
    add(
        "ALPHA_MASK",
        scene
            .materials
            .iter()
            .any(|m| m.flags & material_flags::ALPHA_MASK != 0),
    );
    add(
        "SHADING_NORMALS",
        normal_maps || scene.attributes.iter().any(|a| a.flags & attribute_flags::NORMALS != 0),
    );
    add("THIN_LENS", scene.thin_lens);
    let has = |kind: u32| scene.lights.iter().any(|l| l.kind == kind);
    add("LIGHT_AREA", has(light_kind::AREA));
    add("LIGHT_PUNCTUAL", has(light_kind::POINT) || has(light_kind::SPOT));
    add("LIGHT_POINT", has(light_kind::POINT));
    add("LIGHT_SPOT", has(light_kind::SPOT));
    add("LIGHT_DIRECTIONAL", has(light_kind::DIRECTIONAL));
    add(
        "LIGHT_DELTA",
        has(light_kind::POINT) || has(light_kind::SPOT) || has(light_kind::DIRECTIONAL),
    );
    add("LIGHT_BACKGROUND", has(light_kind::BACKGROUND));
    add("LIGHT_ENVIRONMENT", has(light_kind::ENVIRONMENT));
    add(
        "MEDIA",
        scene.media.info.count > 0 || scene.materials.iter().any(|m| m.flags & material_flags::NULL != 0),
    );
    add("MEDIA_GRID", scene.media.has_grids());
    out
}

/// Every feature flag: kernels that handle any scene.
pub fn all() -> BTreeSet<String> {
    ALL.iter().map(|(f, _)| f.to_string()).collect()
}
