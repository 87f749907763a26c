//! The scene model written as a Mitsuba 3 scene: `scene.xml`, one binary PLY per shape
//! under `meshes/` and the textures the materials use under `textures/` (PNG). What Mitsuba
//! renders is lightgraph's scene as far as both can express it; every material, light or
//! setting the export renders differently is reported in [`Exported::notes`], and what
//! Mitsuba cannot be given at all is an error.
//!
//! The conventions are the importer's ([`super`]), so that importing the export renders the
//! original: the camera as a `lookat` (Mitsuba's +Z forward, +Y up, +X to the image's
//! left), PLY texture coordinates as lightgraph's (Mitsuba 3's too: (0, 0) at the image's top
//! left; a PLY's are not flipped, an OBJ's would be), smooth glass as `dielectric` and perfect
//! mirrors as `conductor` (material `none`), other materials as one-sided `diffuse` (`twosided` for two-sided ones) with
//! the base colour as an sRGB `bitmap`, alpha masks as `mask` with a binary opacity bitmap
//! (the texels' alpha against the cut-off). Media are `homogeneous` media (`sigma_t` over its
//! largest channel, that factor in `scale`, and `albedo`) with an `isotropic` or `hg` phase,
//! referred to as the `interior` and `exterior` of the shapes of materials that have them and
//! by the sensor in one; `null` materials are `null` bsdfs; a scene with media is rendered by
//! `volpath` (Mitsuba's `path` renders no media).

use crate::model::media::{Medium, Phase, uses_media};
use crate::model::texture::{Texture, TextureRef, Wrap, linear_to_srgb8, srgb_to_linear};
use crate::model::{Camera, FovAxis, Light, Look, Material, Rgb, RussianRoulette, Scene, Shape, Vec3};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Mitsuba's continuation probability bound in its `path` integrator's Russian roulette.
const MITSUBA_RR_MAX: f32 = 0.95;

/// A scene written as Mitsuba files, and where it differs from lightgraph's rendering.
#[derive(Debug, Clone, Default)]
pub struct Exported {
    /// The text of `scene.xml`.
    pub xml: String,
    /// Files beside it (path relative to the scene folder, contents).
    pub files: Vec<(String, Vec<u8>)>,
    /// What Mitsuba renders differently from lightgraph, one line each.
    pub notes: Vec<String>,
}

/// Writes `scene` (its glTF asset resolved) at `size` pixels to the folder `dir`
/// (`scene.xml`, `meshes/`, `textures/`); returns the notes of [`export`].
pub fn write(scene: &Scene, size: (u32, u32), dir: &Path) -> Result<Vec<String>, String> {
    let exported = export(scene, size)?;
    for sub in ["meshes", "textures"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(|e| format!("{}: {e}", dir.join(sub).display()))?;
    }
    let files = exported.files.iter().map(|(p, b)| (p.as_str(), b.as_slice()));
    for (path, bytes) in std::iter::once(("scene.xml", exported.xml.as_bytes())).chain(files) {
        let path = dir.join(path);
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(exported.notes)
}

/// The Mitsuba 3 files of `scene` (its glTF asset resolved) rendered at `size` pixels.
pub fn export(scene: &Scene, size: (u32, u32)) -> Result<Exported, String> {
    let mut out = Writer::default();
    out.line("<scene version=\"3.0.0\">");
    out.integrator(scene);
    let mut used: Vec<&str> = scene.shapes.iter().map(Shape::material).collect();
    used.sort();
    used.dedup();
    let mut materials = Vec::new();
    for name in used {
        let material = scene
            .materials
            .get(name)
            .ok_or_else(|| format!("a shape uses material '{name}', which the scene does not define"))?;
        materials.push((name, material));
    }
    let sides = materials.iter().flat_map(|(_, m)| [&m.interior, &m.exterior]);
    for name in sides.chain([&scene.camera_medium]).flatten() {
        if !out.media.contains_key(name) {
            let medium = scene
                .media
                .get(name)
                .ok_or_else(|| format!("medium '{name}' is used but the scene does not define it"))?;
            if medium.grid.is_some() {
                return Err(format!(
                    "medium '{name}' has a density grid: the export writes homogeneous media only"
                ));
            }
            out.medium(name, medium);
        }
    }
    let camera = scene.camera.as_ref().ok_or("the scene has no camera")?;
    let camera_medium = scene.camera_medium.as_ref().map(|name| out.media[name].clone());
    out.sensor(camera, size, camera_medium.as_deref());
    for light in &scene.lights {
        out.light(light)?;
    }
    for (name, material) in &materials {
        out.material(name, material, &scene.textures)?;
    }
    for (i, shape) in scene.shapes.iter().enumerate() {
        out.shape(i, shape, &scene.materials[shape.material()])?;
    }
    out.line("</scene>");
    Ok(Exported {
        xml: out.xml,
        files: out.files,
        notes: out.notes,
    })
}

/// The export being written.
#[derive(Default)]
struct Writer {
    xml: String,
    files: Vec<(String, Vec<u8>)>,
    notes: Vec<String>,
    /// Material name to its XML id.
    ids: BTreeMap<String, String>,
    /// Medium name to its XML id.
    media: BTreeMap<String, String>,
    /// Written images by (texture, kind) to their file name.
    images: BTreeMap<(u32, &'static str), String>,
}

impl Writer {
    fn line(&mut self, text: &str) {
        self.xml.push_str(text);
        self.xml.push('\n');
    }

    /// The `path` integrator (`volpath` for a scene with media) with the scene's path length
    /// and Russian roulette.
    fn integrator(&mut self, scene: &Scene) {
        let settings = &scene.integrator;
        let rr_depth = match settings.russian_roulette {
            RussianRoulette::Throughput { start, max } => {
                if (max - MITSUBA_RR_MAX).abs() > 1e-6 {
                    self.notes.push(format!(
                        "Russian roulette: lightgraph bounds the continuation probability by {max}, Mitsuba by {MITSUBA_RR_MAX}"
                    ));
                }
                start
            }
            RussianRoulette::Albedo => {
                self.notes.push(
                    "Russian roulette: lightgraph's Albedo rule has no Mitsuba equivalent; Mitsuba uses its throughput rule from depth 5 (lightgraph's Throughput(start: 5, max: 0.95))".into(),
                );
                5
            }
        };
        if settings.mis != crate::model::MisHeuristic::Power {
            self.notes.push(
                "MIS: Mitsuba's path integrator uses the power heuristic, the scene the balance heuristic".into(),
            );
        }
        let kind = if uses_media(scene) { "volpath" } else { "path" };
        let _ = writeln!(
            self.xml,
            "  <integrator type=\"{kind}\">\n    <integer name=\"max_depth\" value=\"{}\"/>\n    <integer name=\"rr_depth\" value=\"{rr_depth}\"/>\n    <boolean name=\"hide_emitters\" value=\"false\"/>\n  </integrator>",
            settings.max_path_length
        );
    }

    /// Medium `name` as a homogeneous medium with the id shapes and the sensor refer to:
    /// `sigma_t` over its largest channel (within [0, 1], as Mitsuba's spectral variants want
    /// an `rgb`) with that factor in `scale`, and the `albedo` sigma_s / sigma_t (0 where
    /// nothing is in the way).
    fn medium(&mut self, name: &str, m: &Medium) {
        let id = format!("medium{}", self.media.len());
        self.media.insert(name.to_string(), id.clone());
        let sigma_t: Rgb = std::array::from_fn(|c| m.sigma_a[c] + m.sigma_s[c]);
        let largest = sigma_t.iter().fold(0.0f32, |a, &b| a.max(b));
        let (sigma_t, scale) = if largest > 0.0 {
            (sigma_t.map(|t| t / largest), m.scale * largest)
        } else {
            (sigma_t, m.scale)
        };
        let albedo: Rgb = std::array::from_fn(|c| {
            let t = m.sigma_a[c] + m.sigma_s[c];
            if t > 0.0 { m.sigma_s[c] / t } else { 0.0 }
        });
        let phase = match m.phase {
            Phase::Isotropic => "<phase type=\"isotropic\"/>".to_string(),
            Phase::HenyeyGreenstein { g } => {
                format!("<phase type=\"hg\">\n      <float name=\"g\" value=\"{g}\"/>\n    </phase>")
            }
        };
        let _ = writeln!(
            self.xml,
            "  <!-- {} -->\n  <medium type=\"homogeneous\" id=\"{id}\">\n    {}\n    {}\n    <float name=\"scale\" value=\"{scale}\"/>\n    {phase}\n  </medium>",
            name.replace("--", "- -"),
            rgb_element("sigma_t", sigma_t),
            rgb_element("albedo", albedo),
        );
    }

    /// The pinhole camera with a box-filtered float film of `size`, in the medium of id
    /// `medium`.
    fn sensor(&mut self, camera: &Camera, size: (u32, u32), medium: Option<&str>) {
        let target = match camera.look {
            Look::Target(t) => t,
            Look::Forward(d) => std::array::from_fn(|i| camera.position[i] + d[i]),
        };
        let axis = match camera.fov_axis {
            FovAxis::Horizontal => "x",
            FovAxis::Vertical => "y",
            FovAxis::Smaller => "smaller",
        };
        let medium = medium.map(|id| format!("\n    <ref id=\"{id}\"/>")).unwrap_or_default();
        let _ = writeln!(
            self.xml,
            "  <sensor type=\"perspective\">{medium}\n    <float name=\"fov\" value=\"{}\"/>\n    <string name=\"fov_axis\" value=\"{axis}\"/>\n    <transform name=\"to_world\">\n      <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n    </transform>\n    <sampler type=\"independent\">\n      <integer name=\"sample_count\" value=\"16\"/>\n    </sampler>\n    <film type=\"hdrfilm\">\n      <integer name=\"width\" value=\"{}\"/>\n      <integer name=\"height\" value=\"{}\"/>\n      <string name=\"pixel_format\" value=\"rgb\"/>\n      <string name=\"component_format\" value=\"float32\"/>\n      <rfilter type=\"box\"/>\n    </film>\n  </sensor>",
            camera.fov_degrees,
            list(camera.position),
            list(target),
            list(camera.up),
            size.0,
            size.1
        );
    }

    /// A light that is not an emissive shape.
    fn light(&mut self, light: &Light) -> Result<(), String> {
        let text = match light {
            Light::Directional { direction, irradiance } => format!(
                "  <emitter type=\"directional\">\n    <vector name=\"direction\" {}/>\n    <rgb name=\"irradiance\" value=\"{}\"/>\n  </emitter>",
                xyz(*direction),
                list(*irradiance)
            ),
            Light::Background { radiance, scale } => format!(
                "  <emitter type=\"constant\">\n    <rgb name=\"radiance\" value=\"{}\"/>\n  </emitter>",
                list(radiance.map(|v| v * scale))
            ),
            Light::Point { position, intensity } => format!(
                "  <emitter type=\"point\">\n    <point name=\"position\" {}/>\n    <rgb name=\"intensity\" value=\"{}\"/>\n  </emitter>",
                xyz(*position),
                list(*intensity)
            ),
            Light::Spot { .. } => {
                return Err("spot lights are not exported (Mitsuba's falloff differs from glTF's)".into());
            }
            Light::Environment { file, .. } => return Err(format!("the environment map '{file}' is not exported")),
        };
        self.line(&text);
        Ok(())
    }

    /// Material `name` as a diffuse bsdf (in `twosided` and `mask` as it needs), a specular
    /// one (glass, mirror) or a `null` one, with the id its shapes refer to.
    fn material(&mut self, name: &str, m: &Material, textures: &[Texture]) -> Result<(), String> {
        let id = format!("mat{}", self.ids.len());
        self.ids.insert(name.to_string(), id.clone());
        if m.null {
            let _ = writeln!(
                self.xml,
                "  <!-- {} -->\n  <bsdf type=\"null\" id=\"{id}\"/>",
                name.replace("--", "- -")
            );
            return Ok(());
        }
        let (reflectance, opacity) = match &m.pbr {
            Some(p) => {
                if p.metallic > 0.0 || p.transmission > 0.0 || p.ior != 1.0 || p.emission.iter().any(|&e| e > 0.0) {
                    self.notes.push(format!(
                        "material '{name}': lightgraph renders a specular layer, metal, transmission or emission ({}), Mitsuba only its diffuse base",
                        describe_pbr(p)
                    ));
                }
                let reflectance = match &p.textures.base_color {
                    Some(r) => self.bitmap("reflectance", r, p.base_color, textures, false)?,
                    None => rgb_element("reflectance", p.base_color),
                };
                let opacity = match (p.alpha_cutoff, &p.textures.base_color) {
                    (None, _) => None,
                    (Some(cutoff), Some(r)) if has_alpha(r, textures) => {
                        Some(self.opacity(r, p.alpha, cutoff, textures)?)
                    }
                    (Some(cutoff), _) => Some(format!(
                        "<float name=\"opacity\" value=\"{}\"/>",
                        u8::from(p.alpha >= cutoff)
                    )),
                };
                (reflectance, opacity)
            }
            None if is_pure_specular(m) => {
                let _ = writeln!(
                    self.xml,
                    "  <!-- {} -->\n  {}",
                    name.replace("--", "- -"),
                    specular_bsdf(m, &id)
                );
                return Ok(());
            }
            None => {
                if m.phong.iter().chain(&m.mirror).any(|&v| v > 0.0) {
                    self.notes.push(format!(
                        "material '{name}': its Phong and mirror lobes are left out (Mitsuba: diffuse only)"
                    ));
                }
                (rgb_element("reflectance", m.diffuse), None)
            }
        };
        let mut bsdf = format!("<bsdf type=\"diffuse\">\n      {reflectance}\n    </bsdf>");
        if m.two_sided {
            bsdf = format!("<bsdf type=\"twosided\">\n    {bsdf}\n    </bsdf>");
        }
        if let Some(opacity) = opacity {
            bsdf = format!("<bsdf type=\"mask\">\n    {opacity}\n    {bsdf}\n    </bsdf>");
        }
        let bsdf = bsdf.replacen("<bsdf", &format!("<bsdf id=\"{id}\""), 1);
        let _ = writeln!(self.xml, "  <!-- {} -->\n  {bsdf}", name.replace("--", "- -"));
        Ok(())
    }

    /// A `bitmap` texture element named `slot` of texture reference `r` times `factor`
    /// (written once per texture and factor).
    fn bitmap(
        &mut self,
        slot: &str,
        r: &TextureRef,
        factor: Rgb,
        textures: &[Texture],
        raw: bool,
    ) -> Result<String, String> {
        let t = texture_of(r, textures)?;
        if r.transform != TextureRef::new(0).transform || r.tex_coord != 0 {
            return Err(format!(
                "texture '{}': a texture transform or a second texture coordinate set is not exported",
                t.name
            ));
        }
        let kind: &'static str = if factor == [1.0; 3] { "color" } else { "scaled" };
        let key = (r.texture, kind);
        let file = match self.images.get(&key) {
            Some(f) => f.clone(),
            None => {
                if kind == "scaled" && self.images.keys().any(|&(t, k)| t == r.texture && k == "scaled") {
                    return Err(format!(
                        "texture '{}' is used with two different colour factors",
                        t.name
                    ));
                }
                let file = format!("textures/t{}-{kind}.png", r.texture);
                self.files.push((file.clone(), png_rgb(t, factor, r.linear)?));
                self.images.insert(key, file.clone());
                file
            }
        };
        let wrap = wrap_mode(r, &t.name, &mut self.notes);
        Ok(bitmap_element(slot, &file, wrap, r.nearest, raw || r.linear))
    }

    /// The opacity of an alpha-masked material: the texels' alpha times `alpha` against
    /// `cutoff`, as a binary grey bitmap read as linear (`raw`).
    fn opacity(&mut self, r: &TextureRef, alpha: f32, cutoff: f32, textures: &[Texture]) -> Result<String, String> {
        let t = texture_of(r, textures)?;
        let file = format!("textures/t{}-opacity.png", r.texture);
        if !self.images.contains_key(&(r.texture, "opacity")) {
            let mask: Vec<u8> = t
                .texels
                .iter()
                .map(|&c| {
                    if (c >> 24) as f32 / 255.0 * alpha >= cutoff {
                        255
                    } else {
                        0
                    }
                })
                .collect();
            self.files
                .push((file.clone(), png(t.width, t.height, image::ColorType::L8, &mask)?));
            self.images.insert((r.texture, "opacity"), file.clone());
        }
        self.notes.push(format!(
            "texture '{}': lightgraph cuts out where the bilinearly filtered alpha is below {cutoff}; Mitsuba's mask is stochastic, with the filtered binary opacity (they differ only within a texel of a cut-out's edge)",
            t.name
        ));
        Ok(bitmap_element(
            "opacity",
            &file,
            wrap_mode(r, &t.name, &mut self.notes),
            r.nearest,
            true,
        ))
    }

    /// Shape `i` as a PLY mesh (or an analytic sphere) with its material `m`, the material's
    /// media and its emission.
    fn shape(&mut self, i: usize, shape: &Shape, m: &Material) -> Result<(), String> {
        let id = self
            .ids
            .get(shape.material())
            .ok_or_else(|| format!("shape {i}: material '{}' was not exported", shape.material()))?
            .clone();
        let (head, emission) = match shape {
            Shape::Sphere { center, radius, .. } => (
                format!(
                    "<shape type=\"sphere\">\n    <point name=\"center\" {}/>\n    <float name=\"radius\" value=\"{radius}\"/>",
                    xyz(*center)
                ),
                None,
            ),
            Shape::Triangle { vertices, emission, .. } => (self.ply(i, vertices, &[[0, 1, 2]], None, None)?, *emission),
            Shape::Quad { corners, emission, .. } => {
                (self.ply(i, corners, &[[0, 1, 2], [0, 2, 3]], None, None)?, *emission)
            }
            Shape::Mesh {
                positions,
                indices,
                emission,
                uvs,
                normals,
                ..
            } => (
                self.ply(i, positions, indices, normals.as_deref(), uvs.as_deref())?,
                *emission,
            ),
        };
        let emitter = emission
            .filter(|e| e.iter().any(|&v| v > 0.0))
            .map(|e| {
                format!(
                    "\n    <emitter type=\"area\">\n      {}\n    </emitter>",
                    rgb_element("radiance", e)
                )
            })
            .unwrap_or_default();
        let mut media = String::new();
        for (slot, medium) in [("interior", &m.interior), ("exterior", &m.exterior)] {
            if let Some(name) = medium {
                let _ = write!(media, "\n    <ref name=\"{slot}\" id=\"{}\"/>", self.media[name]);
            }
        }
        let _ = writeln!(self.xml, "  {head}\n    <ref id=\"{id}\"/>{media}{emitter}\n  </shape>");
        Ok(())
    }

    /// Writes a binary PLY of shape `i`; returns the shape element's opening lines.
    fn ply(
        &mut self,
        i: usize,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        normals: Option<&[Vec3]>,
        uvs: Option<&[[f32; 2]]>,
    ) -> Result<String, String> {
        let file = format!("meshes/shape{i}.ply");
        self.files
            .push((file.clone(), ply_bytes(positions, indices, normals, uvs)?));
        Ok(format!(
            "<shape type=\"ply\">\n    <string name=\"filename\" value=\"{file}\"/>\n    <boolean name=\"face_normals\" value=\"{}\"/>",
            normals.is_none()
        ))
    }
}

/// A binary little-endian PLY: float positions, normals and texture coordinates (as they
/// are: Mitsuba 3 reads a PLY's v = 0 as the image's top row), triangles as lists of three
/// ints.
fn ply_bytes(
    positions: &[Vec3],
    indices: &[[u32; 3]],
    normals: Option<&[Vec3]>,
    uvs: Option<&[[f32; 2]]>,
) -> Result<Vec<u8>, String> {
    let n = positions.len();
    if normals.is_some_and(|v| v.len() != n) || uvs.is_some_and(|v| v.len() != n) {
        return Err(format!(
            "a mesh of {n} vertices has normals or texture coordinates of another count"
        ));
    }
    if let Some(bad) = indices.iter().flatten().find(|&&k| k as usize >= n) {
        return Err(format!("a mesh of {n} vertices uses vertex {bad}"));
    }
    let mut header = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\n");
    header.push_str("property float x\nproperty float y\nproperty float z\n");
    if normals.is_some() {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if uvs.is_some() {
        header.push_str("property float u\nproperty float v\n");
    }
    let _ = write!(
        header,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        indices.len()
    );
    let mut bytes = header.into_bytes();
    for k in 0..n {
        let mut values: Vec<f32> = positions[k].to_vec();
        if let Some(normals) = normals {
            values.extend(normals[k]);
        }
        if let Some(uvs) = uvs {
            values.extend(uvs[k]);
        }
        bytes.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    }
    for t in indices {
        bytes.push(3);
        bytes.extend(t.iter().flat_map(|&k| (k as i32).to_le_bytes()));
    }
    Ok(bytes)
}

/// A material of the mirror/dielectric lobe alone (SmallVCM's glass and mirror): no diffuse or
/// Phong lobe, no glTF model.
fn is_pure_specular(m: &Material) -> bool {
    m.pbr.is_none() && m.diffuse.iter().chain(&m.phong).all(|&v| v == 0.0) && m.mirror.iter().any(|&v| v > 0.0)
}

/// The Mitsuba bsdf of a pure specular material, with id `id`: smooth glass (`ior` > 0) as a
/// `dielectric` of that index against 1 (lightgraph scales its reflection by `mirror` and its
/// refraction by nothing, as `specular_reflectance` does), a perfect mirror as a `conductor`
/// of material `none` (reflectance 1) times `mirror`, in `twosided` where the material is.
fn specular_bsdf(m: &Material, id: &str) -> String {
    let tint = if m.mirror == [1.0; 3] {
        String::new()
    } else {
        format!("\n      {}", rgb_element("specular_reflectance", m.mirror))
    };
    if m.ior > 0.0 {
        return format!(
            "<bsdf type=\"dielectric\" id=\"{id}\">\n      <float name=\"int_ior\" value=\"{}\"/>\n      <float name=\"ext_ior\" value=\"1\"/>{tint}\n    </bsdf>",
            m.ior
        );
    }
    let mirror =
        format!("<bsdf type=\"conductor\">\n      <string name=\"material\" value=\"none\"/>{tint}\n    </bsdf>");
    let bsdf = if m.two_sided {
        format!("<bsdf type=\"twosided\">\n    {mirror}\n    </bsdf>")
    } else {
        mirror
    };
    bsdf.replacen("<bsdf", &format!("<bsdf id=\"{id}\""), 1)
}

/// The texture `r` refers to.
fn texture_of<'t>(r: &TextureRef, textures: &'t [Texture]) -> Result<&'t Texture, String> {
    textures
        .get(r.texture as usize)
        .filter(|t| t.width > 0 && t.height > 0)
        .ok_or_else(|| format!("texture {} is missing or empty", r.texture))
}

/// Whether any texel of the texture `r` refers to is not opaque.
fn has_alpha(r: &TextureRef, textures: &[Texture]) -> bool {
    textures
        .get(r.texture as usize)
        .is_some_and(|t| t.texels.iter().any(|&c| c >> 24 != 255))
}

/// The texture's RGB as a PNG (sRGB, or linear when `linear`), scaled by `factor` (in linear)
/// when it is not white.
fn png_rgb(t: &Texture, factor: Rgb, linear: bool) -> Result<Vec<u8>, String> {
    let rgb: Vec<u8> = t
        .texels
        .iter()
        .flat_map(|&c| {
            std::array::from_fn::<u8, 3, _>(|k| {
                let byte = (c >> (8 * k)) as u8;
                if factor[k] == 1.0 {
                    byte
                } else if linear {
                    (byte as f32 * factor[k]).round().clamp(0.0, 255.0) as u8
                } else {
                    linear_to_srgb8(srgb_to_linear(byte as f32 / 255.0) * factor[k])
                }
            })
        })
        .collect();
    png(t.width, t.height, image::ColorType::Rgb8, &rgb)
}

/// Encodes 8-bit pixels as a PNG.
fn png(width: u32, height: u32, color: image::ColorType, pixels: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(encoder, pixels, width, height, color.into()).map_err(|e| e.to_string())?;
    Ok(out)
}

/// Mitsuba's `wrap_mode` of a texture reference (one mode for both axes: a reference with two
/// is noted and exported with its u axis's).
fn wrap_mode(r: &TextureRef, name: &str, notes: &mut Vec<String>) -> &'static str {
    if r.wrap[0] != r.wrap[1] {
        notes.push(format!(
            "texture '{name}': its two wrap modes are exported as the u axis's"
        ));
    }
    match r.wrap[0] {
        Wrap::Repeat => "repeat",
        Wrap::ClampToEdge => "clamp",
        Wrap::MirroredRepeat => "mirror",
    }
}

/// A `bitmap` element named `slot` (nearest or bilinear, `raw`: linear colour).
fn bitmap_element(slot: &str, file: &str, wrap: &str, nearest: bool, raw: bool) -> String {
    let filter = if nearest { "nearest" } else { "bilinear" };
    format!(
        "<texture type=\"bitmap\" name=\"{slot}\">\n        <string name=\"filename\" value=\"{file}\"/>\n        <string name=\"wrap_mode\" value=\"{wrap}\"/>\n        <string name=\"filter_type\" value=\"{filter}\"/>\n        <boolean name=\"raw\" value=\"{raw}\"/>\n      </texture>"
    )
}

fn rgb_element(name: &str, c: Rgb) -> String {
    format!("<rgb name=\"{name}\" value=\"{}\"/>", list(c))
}

fn describe_pbr(p: &crate::model::Pbr) -> String {
    format!(
        "metallic {}, roughness {}, ior {}, transmission {}",
        p.metallic, p.roughness, p.ior, p.transmission
    )
}

/// `x, y, z` as Mitsuba's comma-separated lists.
fn list(v: [f32; 3]) -> String {
    format!("{}, {}, {}", v[0], v[1], v[2])
}

/// `x="" y="" z=""` attributes.
fn xyz(v: [f32; 3]) -> String {
    format!("x=\"{}\" y=\"{}\" z=\"{}\"", v[0], v[1], v[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// cornell-mitsuba as written in its scene file.
    fn cornell() -> Scene {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cornell/cornell-mitsuba.ron");
        crate::parse::scene_file::parse_scene(path, &std::fs::read_to_string(path).unwrap()).unwrap()
    }

    #[test]
    fn cornell_mitsuba_exports_without_notes_and_imports_back() {
        let scene = cornell();
        let dir = std::env::temp_dir().join(format!("lightgraph-export-unit-{}", std::process::id()));
        let notes = write(&scene, (64, 36), &dir).unwrap();
        assert!(
            notes.is_empty(),
            "Mitsuba can render cornell-mitsuba as it is: {notes:?}"
        );
        let back = super::super::load(&dir.join("scene.xml")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let triangles = |s: &Scene| -> usize {
            s.shapes
                .iter()
                .map(|shape| match shape {
                    Shape::Triangle { .. } => 1,
                    Shape::Quad { .. } => 2,
                    Shape::Mesh { indices, .. } => indices.len(),
                    Shape::Sphere { .. } => 0,
                })
                .sum()
        };
        assert_eq!(triangles(&back.scene), triangles(&scene));
        assert_eq!(back.scene.resolution, (64, 36));
        assert_eq!(back.scene.integrator.max_path_length, 8);
        let camera = back.scene.camera.unwrap();
        assert_eq!(camera.position, [0.0, 0.0, 3.9]);
        assert_eq!(camera.fov_axis, FovAxis::Smaller);
        assert_eq!(back.scene.shapes.iter().filter(|s| s.emits()).count(), 1, "the light");
        let unread: Vec<_> = back.warnings.iter().filter(|w| !w.contains("rr_depth")).collect();
        assert!(
            unread.is_empty(),
            "the importer reads all of it but rr_depth: {unread:?}"
        );
    }

    #[test]
    fn media_export_with_their_boundaries_and_import_back_the_same() {
        let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/mitsuba/media.xml");
        let scene = super::super::load(Path::new(data)).unwrap().scene;
        let exported = export(&scene, (8, 8)).unwrap();
        assert!(
            exported.xml.contains("<integrator type=\"volpath\">"),
            "{}",
            exported.xml
        );
        assert!(
            export(&cornell(), (8, 8))
                .unwrap()
                .xml
                .contains("<integrator type=\"path\">")
        );
        let dir = std::env::temp_dir().join(format!("lightgraph-export-media-{}", std::process::id()));
        write(&scene, (8, 8), &dir).unwrap();
        let back = super::super::load(&dir.join("scene.xml"));
        std::fs::remove_dir_all(&dir).unwrap();
        let back = back.unwrap();
        let unexpected: Vec<_> = back.warnings.iter().filter(|w| !w.contains("rr_depth")).collect();
        assert!(unexpected.is_empty(), "{unexpected:?}");
        let back = back.scene;
        // The same medium on each side of each shape, and around the camera.
        let same = |a: Option<&String>, s: &Scene, b: Option<&String>, t: &Scene| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let (m, n) = (&s.media[a], &t.media[b]);
                let close = |x: Rgb, y: Rgb| (0..3).all(|c| (x[c] - y[c]).abs() <= 1e-6 * x[c].max(1.0));
                close(m.sigma_t(), n.sigma_t()) && close(m.sigma_s_scaled(), n.sigma_s_scaled()) && m.phase == n.phase
            }
            _ => false,
        };
        assert!(same(
            scene.camera_medium.as_ref(),
            &scene,
            back.camera_medium.as_ref(),
            &back
        ));
        assert_eq!(back.shapes.len(), scene.shapes.len());
        for (a, b) in scene.shapes.iter().zip(&back.shapes) {
            let (m, n) = (&scene.materials[a.material()], &back.materials[b.material()]);
            assert!(
                same(m.interior.as_ref(), &scene, n.interior.as_ref(), &back),
                "{}",
                a.material()
            );
            assert!(
                same(m.exterior.as_ref(), &scene, n.exterior.as_ref(), &back),
                "{}",
                a.material()
            );
            assert_eq!(m.null, n.null, "{}", a.material());
        }
        assert!(scene.materials.values().any(|m| m.null) && scene.media.len() == 3);
    }

    #[test]
    fn glass_and_mirrors_export_as_dielectric_and_conductor_and_import_back() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cornell/cornell-glossy-background.ron");
        let scene = crate::parse::scene_file::parse_scene(path, &std::fs::read_to_string(path).unwrap()).unwrap();
        let exported = export(&scene, (8, 8)).unwrap();
        assert!(
            exported.xml.contains("type=\"dielectric\"")
                && exported.xml.contains("<float name=\"int_ior\" value=\"1.6\"/>")
                && exported.xml.contains("<string name=\"material\" value=\"none\"/>"),
            "{}",
            exported.xml
        );
        assert!(
            !exported
                .notes
                .iter()
                .any(|n| n.contains("'glass'") || n.contains("'mirror'")),
            "{:?}",
            exported.notes
        );
        let dir = std::env::temp_dir().join(format!("lightgraph-export-glass-{}", std::process::id()));
        write(&scene, (8, 8), &dir).unwrap();
        let back = super::super::load(&dir.join("scene.xml"));
        std::fs::remove_dir_all(&dir).unwrap();
        let back = back.unwrap().scene;
        for (a, b) in scene.shapes.iter().zip(&back.shapes) {
            let (m, n) = (&scene.materials[a.material()], &back.materials[b.material()]);
            if !is_pure_specular(m) {
                continue;
            }
            let p = n
                .pbr
                .as_ref()
                .expect("Mitsuba's dielectric and conductor import as glTF's model");
            if m.ior > 0.0 {
                assert_eq!((p.transmission, p.roughness), (1.0, 0.0), "{}", a.material());
                assert!(
                    (p.ior - m.ior).abs() < 1e-6,
                    "{}: ior {} for {}",
                    a.material(),
                    p.ior,
                    m.ior
                );
            } else {
                assert_eq!(
                    (p.metallic, p.roughness, p.base_color),
                    (1.0, 0.0, m.mirror),
                    "{}",
                    a.material()
                );
            }
        }
    }

    #[test]
    fn what_mitsuba_cannot_render_is_noted_or_refused() {
        let mut scene = cornell();
        scene.integrator.russian_roulette = RussianRoulette::Albedo;
        scene.materials.get_mut("white").unwrap().phong = [0.5; 3];
        let notes = export(&scene, (8, 8)).unwrap().notes;
        assert!(notes.iter().any(|n| n.contains("Albedo")), "{notes:?}");
        assert!(
            notes.iter().any(|n| n.contains("'white'") && n.contains("Phong")),
            "{notes:?}"
        );
        scene.lights.push(Light::Spot {
            position: [0.0; 3],
            direction: [0.0, -1.0, 0.0],
            intensity: [1.0; 3],
            inner_cone_degrees: 0.0,
            outer_cone_degrees: 45.0,
            falloff: Default::default(),
        });
        let e = export(&scene, (8, 8)).unwrap_err();
        assert!(e.contains("spot"), "{e}");
    }
}
