//! GPU mirrors of the scene structs in `shaders/lib/scene.wgsl` (bytemuck, `repr(C)`).
//! A test checks every size and offset against naga's layouter of the WGSL.

use bytemuck::{Pod, Zeroable};

/// Light kinds, as `Light::kind` stores them.
pub mod light_kind {
    /// A triangle emitting on its normal side.
    pub const AREA: u32 = 0;
    /// A point light.
    pub const POINT: u32 = 1;
    /// A directional light.
    pub const DIRECTIONAL: u32 = 2;
    /// A constant background.
    pub const BACKGROUND: u32 = 3;
    /// A spot light: a point light whose intensity falls off outside a cone.
    pub const SPOT: u32 = 4;
    /// An environment map (equirectangular, importance-sampled).
    pub const ENVIRONMENT: u32 = 5;
}

/// Bits of `Material::flags`.
pub mod material_flags {
    /// Both sides of the surface scatter (glTF `doubleSided`): the shading normal faces the
    /// incoming direction.
    pub const TWO_SIDED: u32 = 1;
    /// glTF's metallic-roughness model instead of the SmallVCM lobes.
    pub const PBR: u32 = 2;
    /// Alpha below `alpha_cutoff` is a hole that rays pass through (glTF `MASK`).
    pub const ALPHA_MASK: u32 = 4;
    /// A transmissive PBR material is a thin sheet: light passes straight through it, and its
    /// dielectric reflects as a slab of two faces.
    pub const THIN_WALLED: u32 = 8;
    /// The PBR specular layer's microfacets follow Beckmann's distribution (else GGX).
    pub const BECKMANN: u32 = 16;
    /// Mitsuba's plastic: the PBR diffuse base with the coating's internal scattering.
    pub const PLASTIC: u32 = 32;
    /// With `PLASTIC`: the internal scattering is nonlinear in the base colour.
    pub const PLASTIC_NONLINEAR: u32 = 64;
    /// A PBR metal's Fresnel is a conductor's of complex index `mirror` + i `phong`, tinted by
    /// the base colour (else Schlick's from the base colour).
    pub const CONDUCTOR: u32 = 128;
    /// The PBR microfacets' masking-shadowing is the product of the two directions' maskings
    /// (Mitsuba's, Beckmann's by Walter's fit) instead of height-correlated (glTF's).
    pub const SMITH_SEPARABLE: u32 = 256;
    /// With `PLASTIC`: Mitsuba's rough plastic, whose coating's transmittance and internal
    /// reflectance are a table in `plastic_tables` ([`crate::build::plastic`]) at the offset
    /// `phong_exponent` holds.
    pub const ROUGH_PLASTIC: u32 = 512;
    /// An index-matched boundary between media: rays cross it without a vertex (MEDIA).
    pub const NULL: u32 = 1024;
}

/// Primitive kinds, as `Primitive::kind` stores them.
pub mod primitive_kind {
    /// A triangle: `a` = v0, `b` = v1 - v0, `c` = v2 - v0.
    pub const TRIANGLE: u32 = 0;
    /// A sphere: `a` = centre, `b.x` = radius.
    pub const SPHERE: u32 = 1;
    /// Bit set on a triangle whose material is alpha-masked (`TRIANGLE | ALPHA_MASKED`).
    pub const ALPHA_MASKED: u32 = 2;
}

/// Scene-wide values (`SceneInfo` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuSceneInfo {
    /// Centre of the bounding sphere.
    pub center: [f32; 3],
    /// Radius of the bounding sphere.
    pub radius: f32,
    /// Number of lights.
    pub num_lights: u32,
    /// Index of the background light, or -1.
    pub background: i32,
    /// Number of primitives.
    pub num_primitives: u32,
    /// Number of materials.
    pub num_materials: u32,
}

/// The pinhole camera (`Camera` in WGSL): a ray through raster (x, y) has direction
/// `forward + ndc_x * right + ndc_y * up` with ndc in [-1, 1], y up.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuCamera {
    /// Eye position.
    pub position: [f32; 3],
    /// Image width in pixels.
    pub width: f32,
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Image height in pixels.
    pub height: f32,
    /// Right vector scaled by tan(horizontal fov / 2).
    pub right: [f32; 3],
    /// The thin lens's radius (0: a pinhole).
    pub lens_radius: f32,
    /// Up vector scaled by tan(vertical fov / 2).
    pub up: [f32; 3],
    /// The thin lens's distance to the plane in focus, along `forward`.
    pub focus_distance: f32,
}

/// A triangle or sphere (`Primitive` in WGSL), in BVH order.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuPrimitive {
    /// Triangle v0 or sphere centre.
    pub a: [f32; 3],
    /// Material index.
    pub material: u32,
    /// Triangle edge v1 - v0, or (radius, 0, 0).
    pub b: [f32; 3],
    /// Area light index, or -1.
    pub light: i32,
    /// Triangle edge v2 - v0.
    pub c: [f32; 3],
    /// [`primitive_kind`].
    pub kind: u32,
}

/// A BVH2 node holding both children's boxes (`BvhNode` in WGSL without the `CWBVH` flag). A
/// child with `count == 0` is the inner node at index `first`; otherwise it is a leaf holding
/// primitives `first .. first + count`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuBvhNode {
    /// Left child box minimum.
    pub left_min: [f32; 3],
    /// Left child: node index or first primitive.
    pub left_first: u32,
    /// Left child box maximum.
    pub left_max: [f32; 3],
    /// Left child primitive count (0: inner node).
    pub left_count: u32,
    /// Right child box minimum.
    pub right_min: [f32; 3],
    /// Right child: node index or first primitive.
    pub right_first: u32,
    /// Right child box maximum.
    pub right_max: [f32; 3],
    /// Right child primitive count (0: inner node).
    pub right_count: u32,
}

/// A compressed wide BVH node (`BvhNode` in WGSL when the `CWBVH` flag is set): obvhs's
/// 80-byte `CwBvhNode` (Ylitie et al. 2017, with each axis' minima and maxima stored next to
/// each other), its bytes packed into little-endian u32 words for WGSL: byte `k` of a word
/// sits at bits `8k .. 8k + 8`, and the byte of child `i` in a `[u32; 2]` field is byte
/// `i % 4` of word `i / 4`.
///
/// Child `i`'s box is `p + q * 2^(e - 127)` per axis for its quantized bounds `q` (0..=255)
/// and the axis' exponent byte `e`. Its meta byte is 0 for an empty slot; `0b001_11sss`
/// (`24 + i`, bit 5 set) for an inner node, which is node `child_base` plus the number of
/// inner children in slots below `i`; for a leaf, the primitive count in unary in bits 5..8
/// and the offset of its first primitive from `primitive_base` in bits 0..5.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuCwbvhNode {
    /// Origin of the child grids: the minimum of the node's box.
    pub p: [f32; 3],
    /// Bytes 0..3: the per-axis exponents `e` (biased like an f32's); byte 3: `imask`, bit
    /// `i` set when child `i` is an inner node.
    pub e_imask: u32,
    /// Index of the first inner child node.
    pub child_base: u32,
    /// Index (into the primitives) of the first primitive of the leaf children.
    pub primitive_base: u32,
    /// Meta byte per child.
    pub child_meta: [u32; 2],
    /// Quantized box minimum x per child.
    pub child_min_x: [u32; 2],
    /// Quantized box maximum x per child.
    pub child_max_x: [u32; 2],
    /// Quantized box minimum y per child.
    pub child_min_y: [u32; 2],
    /// Quantized box maximum y per child.
    pub child_max_y: [u32; 2],
    /// Quantized box minimum z per child.
    pub child_min_z: [u32; 2],
    /// Quantized box maximum z per child.
    pub child_max_z: [u32; 2],
}

/// A material (`Material` in WGSL), see [`crate::model::Material`]: the SmallVCM lobes, or
/// with [`material_flags::PBR`] glTF's metallic-roughness model.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Lambertian reflectance, or the PBR base colour.
    pub diffuse: [f32; 3],
    /// Phong exponent; a rough plastic's table offset (`material_flags::ROUGH_PLASTIC`), a
    /// whole number.
    pub phong_exponent: f32,
    /// Phong reflectance.
    pub phong: [f32; 3],
    /// Index of refraction (negative: mirror).
    pub ior: f32,
    /// Mirror/dielectric reflectance.
    pub mirror: [f32; 3],
    /// [`material_flags`].
    pub flags: u32,
    /// Emitted radiance factor (glTF emissiveFactor times emissive strength).
    pub emission: [f32; 3],
    /// PBR metalness.
    pub metallic: f32,
    /// PBR perceptual roughness (GGX alpha = roughness^2).
    pub roughness: f32,
    /// PBR transmission weight (KHR_materials_transmission).
    pub transmission: f32,
    /// Base colour alpha factor.
    pub alpha: f32,
    /// Alpha mask threshold.
    pub alpha_cutoff: f32,
    /// Base colour texture index, or -1.
    pub base_color_texture: i32,
    /// Metallic-roughness texture index (B: metalness, G: roughness), or -1.
    pub metallic_roughness_texture: i32,
    /// Emissive texture index, or -1.
    pub emissive_texture: i32,
    /// Normal texture index, or -1.
    pub normal_texture: i32,
}

impl Default for GpuMaterial {
    fn default() -> Self {
        GpuMaterial {
            ior: -1.0,
            alpha: 1.0,
            base_color_texture: -1,
            metallic_roughness_texture: -1,
            emissive_texture: -1,
            normal_texture: -1,
            ..bytemuck::Zeroable::zeroed()
        }
    }
}

/// A light (`Light` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuLight {
    /// Area: v0; point, spot: position; directional: unit direction of travel.
    pub position: [f32; 3],
    /// [`light_kind`].
    pub kind: u32,
    /// Area: v1 - v0; spot: unit axis (the direction the light shines in).
    pub e1: [f32; 3],
    /// Area: 1 / area.
    pub inv_area: f32,
    /// Area: v2 - v0; spot: x = 1 for Mitsuba's falloff, linear in the angle (0: glTF's).
    pub e2: [f32; 3],
    /// Spot: cosine of the inner cone angle (full intensity inside it).
    pub cos_inner: f32,
    /// Area: unit normal (the emitting side).
    pub normal: [f32; 3],
    /// Spot: cosine of the outer cone angle (no light outside it).
    pub cos_outer: f32,
    /// Radiance (area, background), intensity (point, spot), irradiance (directional), or
    /// the scale of an environment map's radiance.
    pub radiance: [f32; 3],
    /// Unused.
    pub pad2: f32,
}

/// One entry of the light-selection alias table (`AliasEntry` in WGSL, Walker's alias method
/// in integers, [`crate::build::alias`]): of the 2^24 values of a pick's random bits, the slot `i` gets
/// 2^24 / slots; `keep` of them pick light `i`, the others light `other`; `pmf` is the
/// probability with which light `i` is picked overall (entries past the last light: 0).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct GpuAliasEntry {
    /// How many of the slot's values keep its own light.
    pub keep: u32,
    /// The light picked otherwise (the alias; `alias` is a WGSL keyword).
    pub other: u32,
    /// Probability of picking light `i` (the slot's own), for MIS: a whole number of values
    /// over 2^24, exact in f32.
    pub pmf: f32,
}

/// The environment map's shape, orientation and texel layout (`Environment` in WGSL); its
/// texels and sampling distribution are the `env_texels` and `env_cdf` resources.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct GpuEnvironment {
    /// Texels per row (0: no map).
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Cosine of the map's rotation about +Y.
    pub cos_rotation: f32,
    /// Sine of the map's rotation about +Y.
    pub sin_rotation: f32,
    /// 1 when the texel rows span pole to pole ([`crate::model::environment::TexelLayout::PoleToPole`]),
    /// 0 when they sit at their centres.
    pub pole_to_pole: u32,
}

/// Bits of `TextureInfo::flags`.
pub mod texture_flags {
    /// Colour channels are sRGB-encoded: decoded to linear before filtering.
    pub const SRGB: u32 = 1;
    /// Where the wrap mode along u sits (two bits).
    pub const WRAP_S_SHIFT: u32 = 1;
    /// Where the wrap mode along v sits (two bits).
    pub const WRAP_T_SHIFT: u32 = 3;
    /// Wrap mode: repeat.
    pub const WRAP_REPEAT: u32 = 0;
    /// Wrap mode: clamp to the edge texels.
    pub const WRAP_CLAMP: u32 = 1;
    /// Wrap mode: mirrored repeat.
    pub const WRAP_MIRROR: u32 = 2;
    /// Nearest-texel lookups instead of bilinear ones.
    pub const NEAREST: u32 = 32;
    /// A checkerboard: `offset` points at its two colours as f32 RGBA words, texel (x, y)
    /// taking colour (x + y) mod 2 (exact where 8 bits would round them).
    pub const CHECKER: u32 = 64;
}

/// One material slot's texture (`TextureInfo` in WGSL): where its image lies in the texel
/// buffer, its size, wrap modes, sRGB and nearest flags, and the KHR_texture_transform matrix.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuTextureInfo {
    /// First row of the 2x3 texture-coordinate transform.
    pub row0: [f32; 3],
    /// Index of the image's first texel in `texels`.
    pub offset: u32,
    /// Second row of the transform.
    pub row1: [f32; 3],
    /// [`texture_flags`].
    pub flags: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Unused.
    pub pad: [u32; 2],
}

/// Bits of `TriangleAttributes::flags`.
pub mod attribute_flags {
    /// The triangle has vertex normals (`n0`..`n2`).
    pub const NORMALS: u32 = 1;
    /// The triangle is normal-mapped: its tangents are the attributes entry
    /// `flags >> TANGENTS_SHIFT` ([`GpuTriangleAttributes::tangents`]).
    pub const TANGENTS: u32 = 2;
    /// Where the index of the triangle's tangents sits.
    pub const TANGENTS_SHIFT: u32 = 2;
}

/// Per-vertex attributes of one primitive (`TriangleAttributes` in WGSL), in BVH order like
/// the primitives: texture coordinates and unit shading normals, octahedral-encoded in two
/// snorm16 halves (WGSL `unpack2x16snorm`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, Default, PartialEq)]
pub struct GpuTriangleAttributes {
    /// Texture coordinates of v0.
    pub uv0: [f32; 2],
    /// Texture coordinates of v1.
    pub uv1: [f32; 2],
    /// Texture coordinates of v2.
    pub uv2: [f32; 2],
    /// Normal at v0.
    pub n0: u32,
    /// Normal at v1.
    pub n1: u32,
    /// Normal at v2.
    pub n2: u32,
    /// [`attribute_flags`].
    pub flags: u32,
}

impl GpuTriangleAttributes {
    /// The entry (past the primitives' own) holding the tangent frames of a normal-mapped
    /// triangle's `corners` (xyz, w = ±1), of a map of scale `scale`: the unit tangents in
    /// `n0`..`n2` (encoded as normals), the scale in `uv0.x`, the corners' handedness in
    /// `uv1` and `uv2.x`; no flags.
    pub fn tangents(corners: [[f32; 4]; 3], scale: f32) -> Self {
        let [n0, n1, n2] = corners.map(|t| encode_octahedral([t[0], t[1], t[2]]));
        let w = corners.map(|t| if t[3] < 0.0 { -1.0 } else { 1.0 });
        GpuTriangleAttributes {
            uv0: [scale, 0.0],
            uv1: [w[0], w[1]],
            uv2: [w[2], 0.0],
            n0,
            n1,
            n2,
            flags: 0,
        }
    }
}

/// A unit vector in octahedral encoding (Meyer et al. 2010), x in the low 16 bits and y in
/// the high, as snorm16.
pub fn encode_octahedral(n: [f32; 3]) -> u32 {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let (mut x, mut y) = if l1 > 0.0 { (n[0] / l1, n[1] / l1) } else { (0.0, 0.0) };
    if n[2] < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * if ox >= 0.0 { 1.0 } else { -1.0 };
        y = (1.0 - ox.abs()) * if oy >= 0.0 { 1.0 } else { -1.0 };
    }
    let snorm = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    snorm(x) | snorm(y) << 16
}

/// A homogeneous medium (`Medium` in WGSL), see [`crate::model::media::Medium`]: its
/// coefficients already scaled.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub struct GpuMedium {
    /// Scattering coefficient σs per channel.
    pub sigma_s: [f32; 3],
    /// The Henyey-Greenstein mean cosine (0: isotropic).
    pub g: f32,
    /// Extinction coefficient σt = σa + σs per channel.
    pub sigma_t: [f32; 3],
    /// The kind of medium: 0 homogeneous; k > 0: heterogeneous, the density grid k - 1 of
    /// `media_grids` (then the coefficients are per unit density).
    pub kind: u32,
}

/// A heterogeneous medium's density grid and its majorant grid (`media_grids`, six vec4s in
/// WGSL, read by `density_grid_at` in shaders/lib/media_grid.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuDensityGrid {
    /// Rows of the affine map from the world to the unit cube the grid fills.
    pub to_grid: [[f32; 4]; 3],
    /// Voxels along x, y and z.
    pub res: [u32; 3],
    /// Where its densities start in `media_density`.
    pub offset: u32,
    /// Cells of its majorant grid along x, y and z.
    pub cells: [u32; 3],
    /// Where the majorant grid's densities (the largest density each cell can see, x
    /// fastest) start in `media_density`.
    pub majorant_offset: u32,
    /// 0: trilinear; 1: nearest.
    pub nearest: u32,
    /// Padding to 16 bytes.
    pub pad: [u32; 3],
}

/// The media of a material's two sides (`vec2<i32>` in WGSL): indices into the media, -1 for
/// vacuum.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuMaterialMedia {
    /// The medium behind the surface (opposite its normal).
    pub interior: i32,
    /// The medium in front of it.
    pub exterior: i32,
}

/// Scene-wide facts of media (`media_info`, a `vec4<i32>` in WGSL: the camera's medium in x).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub struct GpuMediaInfo {
    /// The medium the camera is in, or -1 (vacuum).
    pub camera_medium: i32,
    /// How many media there are.
    pub count: u32,
    /// Padding to 16 bytes.
    pub pad: [u32; 2],
}
