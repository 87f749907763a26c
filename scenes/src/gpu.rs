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
}

/// Primitive kinds, as `Primitive::kind` stores them.
pub mod primitive_kind {
    /// A triangle: `a` = v0, `b` = v1 - v0, `c` = v2 - v0.
    pub const TRIANGLE: u32 = 0;
    /// A sphere: `a` = centre, `b.x` = radius.
    pub const SPHERE: u32 = 1;
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
    /// Unused.
    pub pad0: f32,
    /// Up vector scaled by tan(vertical fov / 2).
    pub up: [f32; 3],
    /// Unused.
    pub pad1: f32,
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

/// A BVH2 node holding both children's boxes (`BvhNode` in WGSL). A child with
/// `count == 0` is the inner node at index `first`; otherwise it is a leaf holding primitives
/// `first .. first + count`.
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

/// A material (`Material` in WGSL), see [`crate::model::Material`].
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Lambertian reflectance.
    pub diffuse: [f32; 3],
    /// Phong exponent.
    pub phong_exponent: f32,
    /// Phong reflectance.
    pub phong: [f32; 3],
    /// Index of refraction (negative: mirror).
    pub ior: f32,
    /// Mirror/dielectric reflectance.
    pub mirror: [f32; 3],
    /// Unused.
    pub pad: f32,
}

/// A light (`Light` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuLight {
    /// Area: v0; point: position; directional: unit direction of travel.
    pub position: [f32; 3],
    /// [`light_kind`].
    pub kind: u32,
    /// Area: v1 - v0.
    pub e1: [f32; 3],
    /// Area: 1 / area.
    pub inv_area: f32,
    /// Area: v2 - v0.
    pub e2: [f32; 3],
    /// Unused.
    pub pad0: f32,
    /// Area: unit normal (the emitting side).
    pub normal: [f32; 3],
    /// Unused.
    pub pad1: f32,
    /// Radiance (area, background), intensity (point) or irradiance (directional).
    pub radiance: [f32; 3],
    /// Unused.
    pub pad2: f32,
}
