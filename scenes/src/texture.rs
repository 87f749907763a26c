//! Textures: decoded images (RGBA8) and the references materials make to them (wrap modes,
//! KHR_texture_transform), packed for the GPU into one texel buffer and a table of
//! [`GpuTextureInfo`]s (lavapipe has no binding arrays).

use crate::gpu::{GpuTextureInfo, texture_flags};

/// A decoded image, 8 bits per channel.
#[derive(Debug, Clone, Default)]
pub struct Texture {
    /// Where it came from (for messages).
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major texels from the top row, RGBA with R in the low byte of each word.
    pub texels: Vec<u32>,
}

/// How texture coordinates outside [0, 1] map into the image (glTF sampler wrap modes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    /// The image repeats.
    #[default]
    Repeat,
    /// Coordinates clamp to the edge texels.
    ClampToEdge,
    /// The image repeats, every other copy mirrored.
    MirroredRepeat,
}

impl Wrap {
    /// The mode as `TextureInfo::flags` stores it (two bits).
    fn bits(self) -> u32 {
        match self {
            Wrap::Repeat => texture_flags::WRAP_REPEAT,
            Wrap::ClampToEdge => texture_flags::WRAP_CLAMP,
            Wrap::MirroredRepeat => texture_flags::WRAP_MIRROR,
        }
    }
}

/// A material's use of a texture: which image, how it wraps, and the affine map from the
/// mesh's texture coordinates to the image's (KHR_texture_transform; identity without it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::model::Scene::textures`].
    pub texture: u32,
    /// Wrap modes along u (S) and v (T).
    pub wrap: [Wrap; 2],
    /// Rows of the 2x3 matrix: uv' = (row0 · (u, v, 1), row1 · (u, v, 1)).
    pub transform: [[f32; 3]; 2],
    /// The texture coordinate set it reads (glTF TEXCOORD_n).
    pub tex_coord: u32,
}

impl TextureRef {
    /// A reference to `texture` with repeat wrapping and no transform.
    pub fn new(texture: u32) -> TextureRef {
        TextureRef {
            texture,
            wrap: [Wrap::Repeat; 2],
            transform: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            tex_coord: 0,
        }
    }
}

/// The textures of a metallic-roughness material.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PbrTextures {
    /// Base colour (sRGB) and alpha (linear), multiplying the factors.
    pub base_color: Option<TextureRef>,
    /// Roughness in G and metalness in B (linear), multiplying the factors.
    pub metallic_roughness: Option<TextureRef>,
    /// Emission (sRGB), multiplying the emissive factor.
    pub emissive: Option<TextureRef>,
}

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

    /// Adds the table entry of `r` (sRGB-decoded when `srgb`) and returns its index.
    pub fn add(&mut self, r: &TextureRef, srgb: bool, textures: &[Texture]) -> i32 {
        let t = &textures[r.texture as usize];
        let flags = if srgb { texture_flags::SRGB } else { 0 }
            | r.wrap[0].bits() << texture_flags::WRAP_S_SHIFT
            | r.wrap[1].bits() << texture_flags::WRAP_T_SHIFT;
        self.infos.push(GpuTextureInfo {
            row0: r.transform[0],
            offset: self.offsets[r.texture as usize],
            row1: r.transform[1],
            flags,
            width: t.width,
            height: t.height,
            pad: [0; 2],
        });
        self.infos.len() as i32 - 1
    }
}
