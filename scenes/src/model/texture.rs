//! Textures: decoded images (RGBA8) and the references materials make to them (wrap modes,
//! KHR_texture_transform, nearest or bilinear filtering, colour encoding), which [`crate::pack::textures`] packs for the GPU.

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
    /// The texel index along an axis of `n` texels for coordinate `x` (texel units).
    fn index(self, x: f32, n: u32) -> u32 {
        let n_i = n as i64;
        let i = x.floor() as i64;
        let i = match self {
            Wrap::Repeat => i.rem_euclid(n_i),
            Wrap::ClampToEdge => i.clamp(0, n_i - 1),
            Wrap::MirroredRepeat => {
                let k = i.rem_euclid(2 * n_i);
                if k < n_i { k } else { 2 * n_i - 1 - k }
            }
        };
        i as u32
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
    /// Nearest-texel lookups (otherwise bilinear between the four nearest texel centres).
    pub nearest: bool,
    /// The colour channels are linear even where the material slot reads sRGB (Mitsuba's
    /// `raw` bitmaps, procedural textures baked to texels).
    pub linear: bool,
    /// A checkerboard's two linear colours at full precision: its 2 x 2 image holds them in 8
    /// bits (what host code such as exports reads); the GPU reads these, texel (x, y) taking
    /// colour (x + y) mod 2.
    pub checker: Option<[[f32; 3]; 2]>,
}

impl TextureRef {
    /// A reference to `texture` with repeat wrapping, no transform, bilinear filtering and
    /// the slot's colour encoding.
    pub fn new(texture: u32) -> TextureRef {
        TextureRef {
            texture,
            wrap: [Wrap::Repeat; 2],
            transform: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            tex_coord: 0,
            nearest: false,
            linear: false,
            checker: None,
        }
    }
}

impl TextureRef {
    /// The mean linear colour of the texture over the triangle with texture coordinates
    /// `uv` (decoded from sRGB when `srgb` and the reference is not [`TextureRef::linear`]):
    /// the nearest texels at 15 points spread evenly
    /// over the triangle. Used to give an emissive triangle with an emissive texture one
    /// radiance as an area light.
    pub fn mean_over_triangle(&self, textures: &[Texture], uv: [[f32; 2]; 3], srgb: bool) -> [f32; 3] {
        let Some(t) = textures
            .get(self.texture as usize)
            .filter(|t| t.width > 0 && t.height > 0)
        else {
            return [1.0; 3];
        };
        const N: u32 = 5;
        let srgb = srgb && !self.linear;
        let mut sum = [0f64; 3];
        let mut count = 0;
        for i in 0..N {
            for j in 0..N - i {
                let (b1, b2) = ((i as f32 + 1.0 / 3.0) / N as f32, (j as f32 + 1.0 / 3.0) / N as f32);
                let p: [f32; 2] =
                    std::array::from_fn(|k| uv[0][k] + b1 * (uv[1][k] - uv[0][k]) + b2 * (uv[2][k] - uv[0][k]));
                let m = &self.transform;
                let (u, v) = (
                    m[0][0] * p[0] + m[0][1] * p[1] + m[0][2],
                    m[1][0] * p[0] + m[1][1] * p[1] + m[1][2],
                );
                let x = self.wrap[0].index(u * t.width as f32, t.width);
                let y = self.wrap[1].index(v * t.height as f32, t.height);
                let texel = t.texels[(y * t.width + x) as usize];
                for (c, s) in sum.iter_mut().enumerate() {
                    let byte = ((texel >> (8 * c)) & 0xff) as f32 / 255.0;
                    *s += match self.checker {
                        Some(colors) => colors[((x + y) % 2) as usize][c],
                        None if srgb => srgb_to_linear(byte),
                        None => byte,
                    } as f64;
                }
                count += 1;
            }
        }
        sum.map(|s| (s / count as f64) as f32)
    }
}

/// The linear value of an sRGB-encoded one in [0, 1].
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The 8-bit sRGB encoding of a linear value, clamped to [0, 1].
pub fn linear_to_srgb8(linear: f32) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let c = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round() as u8
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
    /// The tangent-space normal map (glTF `normalTexture`).
    pub normal: Option<NormalTexture>,
}

/// A tangent-space normal map (linear RGB, 2 texel - 1 the normal in the frame of tangent,
/// bitangent and normal) and the scale of its tangential components (glTF `normalTexture`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalTexture {
    /// The map.
    pub texture: TextureRef,
    /// Scales the map's x and y before the normal is normalised.
    pub scale: f32,
}

impl PbrTextures {
    /// Whether any texture is set.
    pub fn any(&self) -> bool {
        self.base_color.is_some()
            || self.metallic_roughness.is_some()
            || self.emissive.is_some()
            || self.normal.is_some()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 2 x 1 image: a black texel on the left, a white one on the right.
    pub(crate) fn black_white() -> Vec<Texture> {
        vec![Texture {
            name: "bw".into(),
            width: 2,
            height: 1,
            texels: vec![0xff00_0000, 0xffff_ffff],
        }]
    }

    #[test]
    fn triangle_means_see_the_texels_the_triangle_covers() {
        let r = TextureRef::new(0);
        let right = [[0.55, 0.1], [0.95, 0.1], [0.55, 0.9]];
        assert_eq!(r.mean_over_triangle(&black_white(), right, true), [1.0; 3]);
        let left = [[0.05, 0.1], [0.45, 0.1], [0.05, 0.9]];
        assert_eq!(r.mean_over_triangle(&black_white(), left, true), [0.0; 3]);
        // A checkerboard's colours at full precision, not its image's bytes.
        let checker = TextureRef {
            checker: Some([[0.1, 0.3, 0.7], [0.8, 0.2, 0.21]]),
            ..r
        };
        assert_eq!(
            checker.mean_over_triangle(&black_white(), right, true),
            [0.8, 0.2, 0.21]
        );
        assert_eq!(checker.mean_over_triangle(&black_white(), left, true), [0.1, 0.3, 0.7]);
        // Across both texels: some points on each side, so strictly between.
        let both = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let m = r.mean_over_triangle(&black_white(), both, true)[0];
        assert!(m > 0.0 && m < 1.0, "mean {m}");
        // Repeat wrapping: u + 1 is the same texel.
        let shifted = right.map(|p| [p[0] + 1.0, p[1]]);
        assert_eq!(r.mean_over_triangle(&black_white(), shifted, true), [1.0; 3]);
    }
}
