//! Textures packed for the GPU into one texel buffer and a table of [`GpuTextureInfo`]s
//! (lavapipe has no binding arrays).

use crate::gpu::{GpuTextureInfo, texture_flags};
use crate::model::texture::{Texture, TextureRef, Wrap};

/// Textures packed for the GPU: every image's texels, one after another, and one
/// [`GpuTextureInfo`] per material slot that uses a texture.
#[derive(Debug, Clone, Default)]
pub struct PackedTextures {
    /// The texels of every image (the `texels` resource).
    pub texels: Vec<u32>,
    /// The texture table (the `textures` resource).
    pub infos: Vec<GpuTextureInfo>,
    /// First texel of each image in `texels`.
    offsets: Vec<u32>,
}

impl PackedTextures {
    /// Packs `textures`; fails when they hold more texels than a u32 offset reaches.
    pub fn new(textures: &[Texture]) -> Result<PackedTextures, String> {
        let mut packed = PackedTextures::default();
        for t in textures {
            let offset = u32::try_from(packed.texels.len())
                .map_err(|_| format!("texture '{}': the textures hold more than 2^32 texels", t.name))?;
            packed.offsets.push(offset);
            packed.texels.extend_from_slice(&t.texels);
        }
        Ok(packed)
    }

    /// Adds the table entry of `r` (sRGB-decoded when `srgb` and `r` is not
    /// [`TextureRef::linear`]) and returns its index.
    pub fn add(&mut self, r: &TextureRef, srgb: bool, textures: &[Texture]) -> i32 {
        let t = &textures[r.texture as usize];
        let mut offset = self.offsets[r.texture as usize];
        if let Some(colors) = r.checker {
            // Its two colours as f32 RGBA words after every image.
            offset = self.texels.len() as u32;
            for c in colors {
                self.texels.extend([c[0], c[1], c[2], 1.0].map(f32::to_bits));
            }
        }
        let flags = if srgb && !r.linear { texture_flags::SRGB } else { 0 }
            | if r.nearest { texture_flags::NEAREST } else { 0 }
            | if r.checker.is_some() { texture_flags::CHECKER } else { 0 }
            | wrap_bits(r.wrap[0]) << texture_flags::WRAP_S_SHIFT
            | wrap_bits(r.wrap[1]) << texture_flags::WRAP_T_SHIFT;
        self.infos.push(GpuTextureInfo {
            row0: r.transform[0],
            offset,
            row1: r.transform[1],
            flags,
            width: t.width,
            height: t.height,
            pad: [0; 2],
        });
        self.infos.len() as i32 - 1
    }
}

/// The wrap mode as `TextureInfo::flags` stores it (two bits).
fn wrap_bits(wrap: Wrap) -> u32 {
    match wrap {
        Wrap::Repeat => texture_flags::WRAP_REPEAT,
        Wrap::ClampToEdge => texture_flags::WRAP_CLAMP,
        Wrap::MirroredRepeat => texture_flags::WRAP_MIRROR,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::texture::tests::black_white;

    #[test]
    fn nearest_and_linear_references_set_their_flags() {
        let textures = black_white();
        let mut packed = PackedTextures::new(&textures).unwrap();
        let plain = TextureRef::new(0);
        let nearest_linear = TextureRef {
            nearest: true,
            linear: true,
            wrap: [Wrap::ClampToEdge, Wrap::MirroredRepeat],
            ..plain
        };
        packed.add(&plain, true, &textures);
        packed.add(&nearest_linear, true, &textures);
        assert_eq!(packed.infos[0].flags, texture_flags::SRGB);
        assert_eq!(
            packed.infos[1].flags,
            texture_flags::NEAREST
                | texture_flags::WRAP_CLAMP << texture_flags::WRAP_S_SHIFT
                | texture_flags::WRAP_MIRROR << texture_flags::WRAP_T_SHIFT
        );
        // A linear reference's texels are not decoded: a byte of 128 is 128 / 255.
        let grey = vec![Texture {
            texels: vec![0xff80_8080],
            width: 1,
            height: 1,
            ..Default::default()
        }];
        let uv = [[0.1, 0.1], [0.9, 0.1], [0.1, 0.9]];
        assert_eq!(nearest_linear.mean_over_triangle(&grey, uv, true), [128.0 / 255.0; 3]);
    }
}
