//! The scene model and its RON file format, written by hand: camera, materials, shapes,
//! lights and integrator settings.

pub mod checks;
pub mod enclosure;
pub mod environment;
pub mod framing;
pub mod grid;
pub mod media;
pub mod placement;
pub mod texture;

use serde::Deserialize;
use std::collections::BTreeMap;
use texture::{PbrTextures, Texture};

/// An RGB triple (linear).
pub type Rgb = [f32; 3];
/// A point or direction.
pub type Vec3 = [f32; 3];
/// A tangent of each corner of each triangle: unit xyz, and w = ±1 with the bitangent
/// w (normal × tangent) ([`crate::parse::tangents`] generates them where a mesh has none).
pub type CornerTangents = [[f32; 4]; 3];

/// Rec. 709 luminance of linear RGB (the weights of `luminance` in the WGSL).
pub fn luminance(c: Rgb) -> f64 {
    0.212671 * c[0] as f64 + 0.71516 * c[1] as f64 + 0.072169 * c[2] as f64
}

/// A scene as written in a `.ron` scene file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene shows.
    #[serde(default)]
    pub description: String,
    /// The pinhole camera; optional when the glTF asset provides one (`gltf_camera`) or, for
    /// a bare glTF file, a default framing its bounds.
    #[serde(default)]
    pub camera: Option<Camera>,
    /// A camera of the glTF asset to use instead of `camera`.
    #[serde(default)]
    pub gltf_camera: Option<GltfCamera>,
    /// Default image size (width, height) when none is asked for.
    #[serde(default = "default_resolution")]
    pub resolution: (u32, u32),
    /// Materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    /// Geometry.
    #[serde(default)]
    pub shapes: Vec<Shape>,
    /// Lights that are not emissive shapes.
    #[serde(default)]
    pub lights: Vec<Light>,
    /// Participating media by name (docs/media.md): materials name them as the `interior`
    /// and `exterior` of their surfaces, and `camera_medium` as the camera's.
    #[serde(default)]
    pub media: BTreeMap<String, media::Medium>,
    /// The medium the camera is in (a name of `media`); none: vacuum.
    #[serde(default)]
    pub camera_medium: Option<String>,
    /// Path-sampling settings the scene was specified with.
    #[serde(default)]
    pub integrator: Integrator,
    /// A glTF 2.0 asset (`.gltf` or `.glb`, a path below the asset root) whose meshes join the
    /// shapes: every node's mesh instance with its transform, normals and texture
    /// coordinates; its metallic-roughness materials, with their textures, are named
    /// `gltf:NAME` (see [`crate::parse::gltf`]).
    #[serde(default)]
    pub gltf: Option<String>,
    /// Render the glTF asset's materials as pure Lambertians of their base colour (and
    /// alpha): no specular layer (index of refraction 1), no metal, no transmission, as
    /// Mitsuba's `diffuse` (the scene files compared with Mitsuba set it).
    #[serde(default)]
    pub gltf_diffuse: bool,
    /// Copies of the glTF asset's meshes, each placed by a transform (`At(...)`, `Grid(...)`,
    /// [`placement::Placement`]); none: the asset once, as it places itself. Its
    /// emissive meshes are copied with the rest; its punctual lights and cameras are not.
    #[serde(default)]
    pub gltf_instances: Vec<placement::Placement>,
    /// A Mitsuba scene file (`.xml`, a path below the asset root; not with `gltf`) whose
    /// shapes, materials, textures and emitters join the scene's, and whose sensor is the
    /// camera unless the scene gives one (see [`crate::parse::mitsuba`]); the scene's resolution and
    /// integrator stand.
    #[serde(default)]
    pub mitsuba: Option<String>,
    /// Images the materials' textures refer to (filled by the glTF import).
    #[serde(skip)]
    pub textures: Vec<Texture>,
}

/// A camera of a glTF asset: by its index in the asset's `cameras`, or by the name of the
/// camera or of a node holding it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub enum GltfCamera {
    /// The camera at this index.
    Index(usize),
    /// The camera (or camera node) of this name.
    Name(String),
}

fn default_resolution() -> (u32, u32) {
    (512, 512)
}

/// A pinhole camera.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// Where it looks.
    pub look: Look,
    /// Up direction (made orthogonal to the view direction).
    pub up: Vec3,
    /// Field of view in degrees, across `fov_axis`.
    pub fov_degrees: f32,
    /// The image axis the field of view spans.
    #[serde(default)]
    pub fov_axis: FovAxis,
    /// A thin lens instead of a pinhole: depth of field.
    #[serde(default)]
    pub lens: Option<ThinLens>,
}

/// A thin lens (Mitsuba's `thinlens`): rays start at uniform points of a disk of radius
/// `aperture_radius` across the view direction and meet on the plane in focus, at
/// `focus_distance` along the view direction.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThinLens {
    /// The lens's radius (scene units).
    pub aperture_radius: f32,
    /// The distance of the plane in focus from the lens, along the view direction.
    pub focus_distance: f32,
}

/// The camera's view direction.
#[derive(Debug, Clone, Deserialize)]
pub enum Look {
    /// Along a direction.
    Forward(Vec3),
    /// Towards a point.
    Target(Vec3),
}

/// The image axis a field of view spans (pixels are square).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum FovAxis {
    /// The image width.
    #[default]
    Horizontal,
    /// The image height.
    Vertical,
    /// The shorter of the two.
    Smaller,
}

/// The SmallVCM material: a diffuse lobe, a Phong lobe, and a mirror or dielectric lobe.
/// Lobes with zero reflectance are absent; a material with none is black.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Lambertian reflectance.
    #[serde(default)]
    pub diffuse: Rgb,
    /// Phong reflectance.
    #[serde(default)]
    pub phong: Rgb,
    /// Phong exponent.
    #[serde(default)]
    pub phong_exponent: f32,
    /// Specular reflectance of the mirror/dielectric lobe.
    #[serde(default)]
    pub mirror: Rgb,
    /// Index of refraction; negative means a perfect mirror (Fresnel = 1).
    #[serde(default = "mirror_ior")]
    pub ior: f32,
    /// Whether both sides scatter (glTF `doubleSided`); otherwise the back side is black.
    #[serde(default)]
    pub two_sided: bool,
    /// glTF's metallic-roughness model; when present it replaces the SmallVCM lobes above.
    #[serde(default)]
    pub pbr: Option<Pbr>,
    /// The medium behind the surface (opposite its normal; inside a sphere or a closed mesh
    /// wound outwards), a name of the scene's `media`; none: vacuum.
    #[serde(default)]
    pub interior: Option<String>,
    /// The medium in front of the surface (the side its normal faces); none: vacuum.
    #[serde(default)]
    pub exterior: Option<String>,
    /// An index-matched boundary between media (Mitsuba's `null`): rays cross it unchanged,
    /// without a path vertex, into its `interior` or `exterior`. It has no lobes.
    #[serde(default)]
    pub null: bool,
}

/// glTF 2.0's metallic-roughness material: a diffuse base under a microfacet specular layer
/// (GGX, or Beckmann: `distribution`), metals tinted by the base colour, and optional
/// transmission through a dielectric: the surface of a solid volume (refracting), or a
/// thin-walled sheet (`thin_walled`). With `plastic`, Mitsuba's plastic: the diffuse base
/// also returns the light its coating reflects back into it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pbr {
    /// Base colour (linear).
    #[serde(default = "white")]
    pub base_color: Rgb,
    /// Metalness in [0, 1].
    #[serde(default)]
    pub metallic: f32,
    /// Perceptual roughness in [0, 1] (the distribution's alpha = roughness^2).
    #[serde(default = "unit")]
    pub roughness: f32,
    /// The microfacet distribution of the specular layer.
    #[serde(default)]
    pub distribution: Microfacet,
    /// Smith's masking-shadowing of the microfacets.
    #[serde(default)]
    pub masking: Masking,
    /// Mitsuba's `plastic` and `roughplastic`: the diffuse base's internal scattering.
    #[serde(default)]
    pub plastic: Option<Plastic>,
    /// A metal's complex index of refraction (Mitsuba's conductors): its Fresnel reflectance is
    /// the conductor's, tinted by `base_color`, instead of Schlick's from `base_color`.
    #[serde(default)]
    pub conductor: Option<Conductor>,
    /// Transmission weight in [0, 1] (KHR_materials_transmission).
    #[serde(default)]
    pub transmission: f32,
    /// Index of refraction of the dielectric (KHR_materials_ior).
    #[serde(default = "default_ior")]
    pub ior: f32,
    /// Whether a transmissive material is an infinitely thin sheet (glTF's transmission
    /// without KHR_materials_volume, or with thickness 0) rather than the surface of a solid
    /// volume: light passes straight through it, unbent, and its dielectric reflects as a
    /// slab of two faces. Without transmission it changes nothing.
    #[serde(default)]
    pub thin_walled: bool,
    /// Emitted radiance (glTF emissiveFactor times KHR_materials_emissive_strength).
    #[serde(default)]
    pub emission: Rgb,
    /// Base colour alpha (glTF baseColorFactor's fourth component).
    #[serde(default = "unit")]
    pub alpha: f32,
    /// Alpha mask (glTF alphaMode MASK): where alpha is below this, rays pass through.
    #[serde(default)]
    pub alpha_cutoff: Option<f32>,
    /// Textures scaling the factors (from glTF assets; RON materials have none).
    #[serde(skip)]
    pub textures: PbrTextures,
}

/// How a spot light's intensity falls from the inner cone (θ_i, full) to the outer one (θ_o,
/// none), θ the angle from the axis.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
pub enum SpotFalloff {
    /// glTF's: t² for t = (cos θ − cos θ_o) / (cos θ_i − cos θ_o).
    #[default]
    Smooth,
    /// Mitsuba's: linear in the angle, (θ_o − θ) / (θ_o − θ_i).
    Linear,
}

/// A microfacet distribution of normals, with Smith's masking-shadowing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
pub enum Microfacet {
    /// Trowbridge-Reitz (glTF's).
    #[default]
    Ggx,
    /// Beckmann-Spizzichino (Mitsuba's default).
    Beckmann,
}

/// How a microfacet surface masks and shadows a pair of directions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
pub enum Masking {
    /// 1 / (1 + Lambda(o) + Lambda(i)) (glTF's).
    #[default]
    HeightCorrelated,
    /// G1(o) G1(i) (Mitsuba's: for Beckmann, Walter et al.'s fit of G1 in the BSDF's value).
    Separable,
}

/// Mitsuba's plastic: a diffuse base of reflectance `base_color` under a smooth or rough
/// dielectric coating of index `ior`. The light the base reflects is refracted out through
/// the coating, and the part the coating reflects back inside (its internal diffuse Fresnel
/// reflectance F_dr) reaches the base again, scattered anew: the diffuse lobe is
/// base / (1 - F_dr) (`nonlinear`: base / (1 - base F_dr), a deeper colour) times
/// (1 - F(cos_o)) (1 - F(cos_i)) / (pi ior^2). With a roughness above 0 (Mitsuba's
/// `roughplastic`), the rough coating's transmittances T(cos) and F_dr come from its tables
/// ([`crate::build::plastic`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plastic {
    /// Whether the internal scattering is a geometric series in the base's colour.
    #[serde(default)]
    pub nonlinear: bool,
}

/// A conductor's complex index of refraction eta + i k per channel, relative to the outside;
/// (0, 0) reflects everything (Mitsuba's `none`, a perfect mirror).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Conductor {
    /// The real part.
    pub eta: Rgb,
    /// The imaginary part (absorption).
    pub k: Rgb,
}

fn white() -> Rgb {
    [1.0; 3]
}

fn default_ior() -> f32 {
    1.5
}

impl Default for Pbr {
    fn default() -> Self {
        Pbr {
            base_color: white(),
            metallic: 0.0,
            roughness: 1.0,
            transmission: 0.0,
            ior: default_ior(),
            thin_walled: false,
            distribution: Microfacet::Ggx,
            masking: Masking::HeightCorrelated,
            plastic: None,
            conductor: None,
            emission: [0.0; 3],
            alpha: 1.0,
            alpha_cutoff: None,
            textures: PbrTextures::default(),
        }
    }
}

fn mirror_ior() -> f32 {
    -1.0
}

impl Default for Material {
    fn default() -> Self {
        Material {
            diffuse: [0.0; 3],
            phong: [0.0; 3],
            phong_exponent: 0.0,
            mirror: [0.0; 3],
            ior: mirror_ior(),
            two_sided: false,
            pbr: None,
            interior: None,
            exterior: None,
            null: false,
        }
    }
}

/// A piece of geometry. Triangles face the side their winding gives by the right-hand
/// rule ((v1 - v0) x (v2 - v0)); diffuse and glossy surfaces are black from behind.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Shape {
    /// One triangle.
    Triangle {
        /// The corners.
        vertices: [Vec3; 3],
        /// Material name.
        material: String,
        /// Emitted radiance (one-sided, along the normal): makes it an area light.
        #[serde(default)]
        emission: Option<Rgb>,
    },
    /// A planar quad, split into (c0, c1, c2) and (c0, c2, c3).
    Quad {
        /// The corners, in order around the quad.
        corners: [Vec3; 4],
        /// Material name.
        material: String,
        /// Emitted radiance: makes both triangles area lights.
        #[serde(default)]
        emission: Option<Rgb>,
    },
    /// An indexed triangle mesh (each triangle faces by its winding, as `Triangle`).
    Mesh {
        /// Vertex positions.
        positions: Vec<Vec3>,
        /// Three vertex indices per triangle.
        indices: Vec<[u32; 3]>,
        /// Material name.
        material: String,
        /// Emitted radiance: makes every triangle an area light.
        #[serde(default)]
        emission: Option<Rgb>,
        /// Texture coordinates per vertex (glTF TEXCOORD_n); (0, 0) without them.
        #[serde(default)]
        uvs: Option<Vec<[f32; 2]>>,
        /// Unit shading normals per vertex, on the side the winding's normal faces; the
        /// geometric normal without them (flat shading).
        #[serde(default)]
        normals: Option<Vec<Vec3>>,
        /// Tangents of each triangle's corners for its material's normal map: unit xyz and
        /// w = ±1, the bitangent w (normal × tangent) (glTF TANGENT, or MikkTSpace's).
        #[serde(default)]
        tangents: Option<Vec<CornerTangents>>,
    },
    /// An analytic sphere (normals face outward).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Material name.
        material: String,
    },
}

impl Shape {
    /// The shape's material name.
    pub fn material(&self) -> &str {
        match self {
            Shape::Triangle { material, .. }
            | Shape::Quad { material, .. }
            | Shape::Mesh { material, .. }
            | Shape::Sphere { material, .. } => material,
        }
    }

    /// Whether the shape emits light.
    pub fn emits(&self) -> bool {
        match self {
            Shape::Triangle { emission, .. } | Shape::Quad { emission, .. } | Shape::Mesh { emission, .. } => {
                emission.is_some_and(|e| e.iter().any(|&v| v > 0.0))
            }
            Shape::Sphere { .. } => false,
        }
    }
}

/// Lights that are not emissive shapes.
#[derive(Debug, Clone, Deserialize)]
pub enum Light {
    /// An isotropic point light.
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (W/sr).
        intensity: Rgb,
    },
    /// A distant light.
    Directional {
        /// Direction the light travels in (normalised on load).
        direction: Vec3,
        /// Irradiance on a surface perpendicular to the direction.
        irradiance: Rgb,
    },
    /// A constant environment seen in every direction nothing else is.
    Background {
        /// Radiance.
        radiance: Rgb,
        /// Scale applied to the radiance.
        #[serde(default = "unit")]
        scale: f32,
    },
    /// A point light shining into a cone, full inside the inner cone, dark outside the outer
    /// one, and between them falling off by `falloff`.
    Spot {
        /// Position.
        position: Vec3,
        /// The axis: the direction the light shines in (normalised on load).
        direction: Vec3,
        /// Radiant intensity on the axis (W/sr).
        intensity: Rgb,
        /// Half-angle of the cone of full intensity, in degrees (glTF's default 0).
        #[serde(default)]
        inner_cone_degrees: f32,
        /// Half-angle outside which there is no light, in degrees, at most 90 (glTF's
        /// default 45).
        #[serde(default = "default_outer_cone")]
        outer_cone_degrees: f32,
        /// The falloff between the cones.
        #[serde(default)]
        falloff: SpotFalloff,
    },
    /// An equirectangular environment map seen in every direction nothing else is
    /// (`.hdr` or `.exr`, a path below the asset root): +Y is up (the top row), the image's
    /// centre column looks along −Z and u grows towards +X (u = 0 and 1 are +Z); filtered
    /// bilinearly (see [`crate::model::environment`]).
    Environment {
        /// The image file, below the asset root.
        file: String,
        /// Scale applied to the radiance.
        #[serde(default = "unit")]
        scale: f32,
        /// Rotation of the map about +Y, counter-clockwise seen from above.
        #[serde(default)]
        rotation_degrees: f32,
        /// Where the texels sit, between which the radiance is interpolated bilinearly:
        /// `Centred` (the default) or `PoleToPole` (Mitsuba's envmap, set by its importer).
        #[serde(default)]
        layout: environment::TexelLayout,
        /// The decoded map, once the scene's assets are resolved.
        #[serde(skip)]
        map: Option<std::sync::Arc<environment::EnvironmentMap>>,
    },
}

fn default_outer_cone() -> f32 {
    45.0
}

fn unit() -> f32 {
    1.0
}

/// How paths are sampled, as the scene was specified.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Integrator {
    /// Most path segments from the camera to a light (1 = directly visible lights only).
    #[serde(default = "default_max_path_length")]
    pub max_path_length: u32,
    /// Russian roulette rule.
    #[serde(default)]
    pub russian_roulette: RussianRoulette,
    /// Multiple importance sampling heuristic.
    #[serde(default)]
    pub mis: MisHeuristic,
}

fn default_max_path_length() -> u32 {
    10
}

impl Default for Integrator {
    fn default() -> Self {
        Integrator {
            max_path_length: default_max_path_length(),
            russian_roulette: RussianRoulette::default(),
            mis: MisHeuristic::default(),
        }
    }
}

/// When paths are terminated at random.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Default)]
pub enum RussianRoulette {
    /// At every vertex, continue with the material's albedo bound (SmallVCM's rule).
    #[default]
    Albedo,
    /// From vertex `start` on, continue with min(max throughput component, `max`)
    /// (Mitsuba 3's rule).
    Throughput {
        /// First vertex (1 = the first surface hit) at which roulette applies.
        start: u32,
        /// Highest continuation probability.
        max: f32,
    },
}

/// The heuristic that weights strategies in MIS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
pub enum MisHeuristic {
    /// Balance heuristic.
    #[default]
    Balance,
    /// Power heuristic (exponent 2).
    Power,
}
