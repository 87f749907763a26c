//! Materials as the GPU reads them: their flags, texture slots and rough plastics' coating
//! tables.

use super::textures::PackedTextures;
use crate::build::plastic;
use crate::gpu::{self, GpuMaterial};
use crate::model::{self, texture};

/// A material as the GPU reads it, its textures added to `packed` and a rough plastic's
/// coating table to `tables`.
pub(crate) fn gpu_material(
    m: &model::Material,
    packed: &mut PackedTextures,
    textures: &[texture::Texture],
    tables: &mut plastic::PlasticTables,
) -> Result<GpuMaterial, String> {
    let side_flags = if m.two_sided { gpu::material_flags::TWO_SIDED } else { 0 }
        | if m.null { gpu::material_flags::NULL } else { 0 };
    Ok(match &m.pbr {
        None => GpuMaterial {
            diffuse: m.diffuse,
            phong_exponent: m.phong_exponent,
            phong: m.phong,
            ior: m.ior,
            mirror: m.mirror,
            flags: side_flags,
            ..GpuMaterial::default()
        },
        Some(p) => {
            let mut slot = |r: &Option<texture::TextureRef>, srgb: bool| match r {
                None => Ok(-1),
                Some(r) if (r.texture as usize) < textures.len() => Ok(packed.add(r, srgb, textures)),
                Some(r) => Err(format!("texture {} of {}", r.texture, textures.len())),
            };
            let mask = if p.alpha_cutoff.is_some() {
                gpu::material_flags::ALPHA_MASK
            } else {
                0
            };
            let thin = if p.thin_walled && p.transmission > 0.0 {
                gpu::material_flags::THIN_WALLED
            } else {
                0
            };
            let (eta, k) = p.conductor.map_or(([0.0; 3], [0.0; 3]), |c| (c.eta, c.k));
            let table = rough_plastic_table(p, tables)?;
            let rough_plastic = if table.is_some() {
                gpu::material_flags::ROUGH_PLASTIC
            } else {
                0
            };
            GpuMaterial {
                diffuse: p.base_color,
                phong_exponent: table.unwrap_or(0) as f32,
                ior: p.ior,
                mirror: eta,
                phong: k,
                flags: side_flags | gpu::material_flags::PBR | mask | thin | rough_plastic | pbr_model_flags(p),
                emission: p.emission,
                metallic: p.metallic,
                roughness: p.roughness,
                transmission: p.transmission,
                alpha: p.alpha,
                alpha_cutoff: p.alpha_cutoff.unwrap_or(0.0),
                base_color_texture: slot(&p.textures.base_color, true)?,
                metallic_roughness_texture: slot(&p.textures.metallic_roughness, false)?,
                emissive_texture: slot(&p.textures.emissive, true)?,
                normal_texture: slot(&p.textures.normal.map(|n| n.texture), false)?,
            }
        }
    })
}

/// The offset in `tables` of a rough plastic's coating table (added on first use); `None` for
/// other materials, smooth plastics among them.
fn rough_plastic_table(p: &model::Pbr, tables: &mut plastic::PlasticTables) -> Result<Option<u32>, String> {
    if p.plastic.is_none() || p.roughness <= 0.0 {
        return Ok(None);
    }
    let offset = tables.offset(p.roughness.min(1.0), p.ior, p.distribution)?;
    // The GPU reads the offset from an f32, exact below 2^24.
    if offset >= 1 << 24 {
        return Err("too many rough plastic coatings: their tables exceed 2^24 floats".to_string());
    }
    Ok(Some(offset))
}

/// The flags of a PBR material's microfacet distribution and plastic model.
fn pbr_model_flags(p: &model::Pbr) -> u32 {
    let beckmann = match p.distribution {
        model::Microfacet::Ggx => 0,
        model::Microfacet::Beckmann => gpu::material_flags::BECKMANN,
    };
    let plastic = match p.plastic {
        None => 0,
        Some(model::Plastic { nonlinear: false }) => gpu::material_flags::PLASTIC,
        Some(model::Plastic { nonlinear: true }) => {
            gpu::material_flags::PLASTIC | gpu::material_flags::PLASTIC_NONLINEAR
        }
    };
    let conductor = if p.conductor.is_some() {
        gpu::material_flags::CONDUCTOR
    } else {
        0
    };
    let separable = match p.masking {
        model::Masking::HeightCorrelated => 0,
        model::Masking::Separable => gpu::material_flags::SMITH_SEPARABLE,
    };
    beckmann | plastic | conductor | separable
}
