//! glTF 2.0 import (`.gltf` and `.glb`, through the `gltf` crate): every mesh instance of the
//! default scene, flattened with its node transform into [`Shape::Mesh`]es with their normals
//! and texture coordinates; metallic-roughness materials ([`Pbr`]) with their base-colour,
//! metallic-roughness and emissive textures (KHR_texture_transform), alpha mask,
//! KHR_materials_emissive_strength, KHR_materials_transmission (thin-walled, or through a solid
//! volume with KHR_materials_volume: `MaterialImport::thin_walled`, its attenuation an
//! absorbing medium inside: `MaterialImport::attenuation`), KHR_materials_ior and
//! KHR_materials_specular (as an index of refraction, `MaterialImport::specular_ior`); and
//! the perspective cameras the scene's nodes place, and the KHR_lights_punctual lights of its
//! nodes ([`punctual_light`]). Other extensions the file uses are reported as warnings.

use crate::model::CornerTangents;
use crate::model::media::Medium;
use crate::model::texture::{NormalTexture, PbrTextures, Texture, TextureRef, Wrap};
use crate::model::{Camera, FovAxis, Light, Look, Material, Pbr, Rgb, Shape, SpotFalloff};
use crate::parse::tangents;
use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use std::collections::BTreeMap;
use std::path::Path;

/// What a glTF file adds to a scene.
#[derive(Debug, Clone, Default)]
pub struct Imported {
    /// One mesh shape per primitive instance.
    pub shapes: Vec<Shape>,
    /// Materials by name (`gltf:NAME` or `gltf:#INDEX`).
    pub materials: BTreeMap<String, Material>,
    /// The absorbing media inside transmissive volumes (KHR_materials_volume), each named
    /// after its material.
    pub media: BTreeMap<String, Medium>,
    /// Triangles imported.
    pub triangles: usize,
    /// KHR_lights_punctual lights placed by their nodes.
    pub lights: Vec<Light>,
    /// Images the materials' textures use; [`TextureRef::texture`] indexes them.
    pub textures: Vec<Texture>,
    /// Perspective cameras placed by the scene's nodes.
    pub cameras: Vec<ImportedCamera>,
    /// What was imported only approximately (one line each).
    pub warnings: Vec<String>,
}

/// A camera of the asset, placed by the first node holding it.
#[derive(Debug, Clone)]
pub struct ImportedCamera {
    /// Its index in the asset's `cameras`.
    pub index: usize,
    /// Its name and its node's name, where they have one.
    pub names: Vec<String>,
    /// The camera (vertical field of view).
    pub camera: Camera,
    /// Width over height, when the asset gives it.
    pub aspect_ratio: Option<f32>,
}

/// Whether `uri` percent-decodes to UTF-8.
fn percent_decodes(uri: &str) -> bool {
    let bytes = uri.as_bytes();
    let hex = |j: usize| bytes.get(j).and_then(|&c| (c as char).to_digit(16));
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match (bytes[i], hex(i + 1), hex(i + 2)) {
            (b'%', Some(high), Some(low)) => {
                decoded.push((high * 16 + low) as u8);
                i += 3;
            }
            (c, ..) => {
                decoded.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8(decoded).is_ok()
}

/// Reads, checks and validates the document at `path`, then its buffers and images, like
/// `gltf::import` but refusing what makes the `gltf` crate panic.
fn load(path: &Path) -> Result<(gltf::Document, Vec<gltf::buffer::Data>, Vec<gltf::image::Data>), String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let gltf = gltf::Gltf::from_reader_without_validation(std::io::BufReader::new(file)).map_err(|e| e.to_string())?;
    let json = gltf.document.into_json();
    // gltf-json's validation indexes the accessors with POSITION unchecked.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &primitive.attributes {
                if accessor.value() >= json.accessors.len() {
                    return Err(format!(
                        "mesh {m}, primitive {p}: attribute {} uses accessor {}, but there are {}",
                        semantic.to_string(),
                        accessor.value(),
                        json.accessors.len()
                    ));
                }
            }
        }
    }
    // gltf's import unwraps the percent-decoding of relative URIs.
    let buffer_uris = json
        .buffers
        .iter()
        .enumerate()
        .map(|(i, b)| (format!("buffer {i}"), &b.uri));
    let image_uris = json
        .images
        .iter()
        .enumerate()
        .map(|(i, b)| (format!("image {i}"), &b.uri));
    for (what, uri) in buffer_uris.chain(image_uris) {
        if let Some(uri) = uri
            && !uri.contains(':')
            && !percent_decodes(uri)
        {
            return Err(format!("{what}: URI '{uri}' does not percent-decode to UTF-8"));
        }
    }
    // gltf's Image::source unwraps these.
    for (i, image) in json.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => return Err(format!("image {i} has neither a uri nor a bufferView")),
            (_, Some(_), None) => return Err(format!("image {i} has a bufferView but no mimeType")),
            _ => {}
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    // gltf slices buffers by views unchecked.
    for view in document.views() {
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|end| end > view.buffer().length()) {
            return Err(format!(
                "buffer view {} (bytes {}..+{}) lies beyond its buffer {} of {} bytes",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                view.buffer().length()
            ));
        }
    }
    let base = path.parent();
    let buffers = gltf::import_buffers(&document, base, gltf.blob).map_err(|e| e.to_string())?;
    let images = document
        .images()
        .map(|image| {
            gltf::image::Data::from_source(image.source(), base, &buffers).map_err(|e| {
                let source = match image.source() {
                    gltf::image::Source::Uri { uri, .. } => format!(" ('{uri}')"),
                    gltf::image::Source::View { .. } => String::new(),
                };
                format!("image {}{source}: {e}", image.index())
            })
        })
        .collect::<Result<_, _>>()?;
    Ok((document, buffers, images))
}

/// Checks what gltf's reader assumes of an accessor: not sparse (a huge sparse count would
/// allocate without bound), of one of `types` and of `dimensions`, with at least one element,
/// all within its buffer view.
fn check_accessor(a: &gltf::Accessor, types: &[DataType], dimensions: Dimensions) -> Result<(), String> {
    let i = a.index();
    if a.sparse().is_some() {
        return Err(format!("accessor {i} is sparse, which lightgraph does not support"));
    }
    if !types.contains(&a.data_type()) || a.dimensions() != dimensions {
        return Err(format!(
            "accessor {i} holds {:?} of {:?}; expected {dimensions:?} of {types:?}",
            a.dimensions(),
            a.data_type()
        ));
    }
    let view = a.view().ok_or_else(|| format!("accessor {i} has no bufferView"))?;
    let (count, size) = (a.count(), a.size());
    let stride = view.stride().unwrap_or(size);
    if count == 0 || stride < size {
        return Err(format!(
            "accessor {i} has {count} elements of {size} bytes every {stride} bytes"
        ));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(size + a.offset()));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "accessor {i}: {count} elements of {size} bytes every {stride} bytes from byte {} do not fit its \
             buffer view {} of {} bytes",
            a.offset(),
            view.index(),
            view.length()
        ));
    }
    Ok(())
}

/// The index of refraction whose dielectric reflectance at normal incidence is `f0` (< 1).
fn ior_of_reflectance(f0: f32) -> f32 {
    let r = f0.max(0.0).sqrt();
    (1.0 + r) / (1.0 - r)
}

/// glTF extensions the importer reads.
const SUPPORTED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// Extensions that change nothing a render shows (metadata).
const WITHOUT_EFFECT: &[&str] = &["KHR_xmp", "KHR_xmp_json_ld"];

/// Imports `path`; errors name the file and the problem.
pub fn import(path: &Path) -> Result<Imported, String> {
    let shown = path.display();
    let (document, buffers, images) = load(path).map_err(|e| format!("{shown}: {e}"))?;
    for required in document.extensions_required() {
        if !SUPPORTED.contains(&required) {
            return Err(format!(
                "{shown}: requires the glTF extension {required}, which lightgraph does not support"
            ));
        }
    }
    let mut out = Imported::default();
    for used in document.extensions_used() {
        if !SUPPORTED.contains(&used) && !WITHOUT_EFFECT.contains(&used) {
            out.warnings.push(format!(
                "uses the glTF extension {used}, which lightgraph does not read: rendered without it"
            ));
        }
    }
    let mut materials = MaterialImport {
        images: &images,
        image_texture: vec![None; images.len()],
        out: &mut out,
    };
    let mut material_uses = Vec::new();
    for m in document.materials() {
        material_uses.push(materials.material(&m).map_err(|e| format!("{shown}: {e}"))?);
    }
    let default_material = "gltf:default".to_string();
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| format!("{shown}: no scene"))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    // The node hierarchy must be disjoint trees: a node reached twice closes a cycle (which
    // would never end) or has two parents.
    let mut reached = vec![false; document.nodes().len()];
    let mut camera_nodes: Vec<Option<(Option<String>, Mat4)>> = vec![None; document.cameras().len()];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[node.index()], true) {
            return Err(format!(
                "{shown}: node {} is reached twice from the scene (a cycle, or two parents)",
                node.index()
            ));
        }
        let transform = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        for child in node.children() {
            stack.push((child, transform));
        }
        if let Some(light) = node.light() {
            out.lights
                .push(punctual_light(&light, &transform).map_err(|e| format!("{shown}: node {}: {e}", node.index()))?);
        }
        if let Some(camera) = node.camera() {
            camera_nodes[camera.index()].get_or_insert((node.name().map(String::from), transform));
        }
        let Some(mesh) = node.mesh() else { continue };
        let mesh_name = mesh.name().unwrap_or("?");
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                return Err(format!(
                    "{shown}: mesh '{mesh_name}' has a primitive of mode {:?}; only triangles are supported",
                    primitive.mode()
                ));
            }
            let material = match primitive.material().index() {
                Some(i) => material_uses[i].clone(),
                None => {
                    out.materials.entry(default_material.clone()).or_insert(Material {
                        diffuse: [0.8; 3],
                        ..Default::default()
                    });
                    MaterialUse {
                        name: default_material.clone(),
                        emission: [0.0; 3],
                        uv_set: 0,
                        normal_mapped: false,
                    }
                }
            };
            let Some(data) = read_primitive(&primitive, &buffers, transform, &material)
                .map_err(|e| format!("{shown}: mesh '{mesh_name}': {e}"))?
            else {
                continue;
            };
            let emission = material.emission;
            out.triangles += data.indices.len();
            out.shapes.push(Shape::Mesh {
                positions: data.positions,
                indices: data.indices,
                material: material.name,
                emission: emission.iter().any(|&e| e > 0.0).then_some(emission),
                uvs: data.uvs,
                normals: data.normals,
                tangents: data.tangents,
            });
        }
    }
    if out.triangles == 0 {
        return Err(format!("{shown}: no triangles in the default scene"));
    }
    out.cameras = cameras(&document, &camera_nodes);
    Ok(out)
}

/// A KHR_lights_punctual light placed by its node's world `transform`: at the node's origin,
/// shining along the node's −Z axis, with colour × intensity. Units: lightgraph is
/// radiometric, so glTF's photometric intensity is taken as is, as radiant intensity in W/sr
/// (point, spot) and irradiance in W/m² (directional), with no 683 lm/W conversion: scenes
/// authored for a physical camera's exposure come out bright, which `--exposure` corrects.
/// `range` is ignored (a physically based renderer lets light fall off with the inverse
/// square law only; the extension allows it). Spot cones keep glTF's smooth falloff.
fn punctual_light(light: &gltf::khr_lights_punctual::Light, transform: &Mat4) -> Result<Light, String> {
    use gltf::khr_lights_punctual::Kind;
    let color = light.color();
    let intensity = light.intensity();
    if !(intensity.is_finite() && intensity >= 0.0) || color.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
        return Err(format!(
            "light {}: colour {color:?} and intensity {intensity} must be finite and non-negative",
            light.index()
        ));
    }
    let value = color.map(|c| c * intensity);
    let position = transform.transform_point3(Vec3::ZERO).to_array();
    let direction = transform.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if direction == Vec3::ZERO && !matches!(light.kind(), Kind::Point) {
        return Err(format!(
            "light {}: its node's transform has no −Z direction",
            light.index()
        ));
    }
    Ok(match light.kind() {
        Kind::Point => Light::Point {
            position,
            intensity: value,
        },
        Kind::Directional => Light::Directional {
            direction: direction.to_array(),
            irradiance: value,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            if !(0.0 <= inner_cone_angle
                && inner_cone_angle <= outer_cone_angle
                && outer_cone_angle <= std::f32::consts::FRAC_PI_2)
            {
                return Err(format!(
                    "light {}: spot cone angles inner {inner_cone_angle} and outer {outer_cone_angle} radians must satisfy 0 <= inner <= outer <= pi/2",
                    light.index()
                ));
            }
            Light::Spot {
                position,
                direction: direction.to_array(),
                intensity: value,
                inner_cone_degrees: inner_cone_angle.to_degrees(),
                outer_cone_degrees: outer_cone_angle.to_degrees(),
                falloff: SpotFalloff::Smooth,
            }
        }
    })
}

/// A mesh primitive read from its accessors, in world space.
struct MeshData {
    positions: Vec<[f32; 3]>,
    indices: Vec<[u32; 3]>,
    uvs: Option<Vec<[f32; 2]>>,
    normals: Option<Vec<[f32; 3]>>,
    tangents: Option<Vec<CornerTangents>>,
}

/// Reads a triangle primitive's positions, indices, normals, texture coordinates (the set
/// `material` reads) and, where `material` has a normal map, tangents (the file's, else
/// MikkTSpace's), placed by `transform`; `None` when it has no positions.
fn read_primitive(
    primitive: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    transform: Mat4,
    material: &MaterialUse,
) -> Result<Option<MeshData>, String> {
    let uv_set = material.uv_set;
    let f32_only = &[DataType::F32][..];
    let uv_types = &[DataType::F32, DataType::U8, DataType::U16][..];
    let positions = primitive
        .get(&gltf::Semantic::Positions)
        .map(|a| (a, f32_only, Dimensions::Vec3));
    let normals = primitive
        .get(&gltf::Semantic::Normals)
        .map(|a| (a, f32_only, Dimensions::Vec3));
    let uvs = primitive
        .get(&gltf::Semantic::TexCoords(uv_set))
        .map(|a| (a, uv_types, Dimensions::Vec2));
    let tangents = primitive
        .get(&gltf::Semantic::Tangents)
        .filter(|_| material.normal_mapped)
        .map(|a| (a, f32_only, Dimensions::Vec4));
    let indices = primitive
        .indices()
        .map(|a| (a, &[DataType::U8, DataType::U16, DataType::U32][..], Dimensions::Scalar));
    let accessors = positions
        .into_iter()
        .chain(normals)
        .chain(uvs)
        .chain(tangents)
        .chain(indices);
    for (accessor, types, dimensions) in accessors {
        check_accessor(&accessor, types, dimensions)?;
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = reader.read_positions() else {
        return Ok(None);
    };
    let local_positions: Vec<[f32; 3]> = positions.collect();
    let positions: Vec<[f32; 3]> = local_positions
        .iter()
        .map(|&p| transform.transform_point3(Vec3::from_array(p)).to_array())
        .collect();
    let vertices = positions.len();
    let per_vertex = |what: &str, count: usize| {
        if count == vertices {
            Ok(())
        } else {
            Err(format!("{count} {what} for {vertices} vertices"))
        }
    };
    // Normals are covectors: they map by the inverse transpose, which keeps them on the side
    // the (possibly re-wound) triangles face.
    let normal_matrix = glam::Mat3::from_mat4(transform).inverse().transpose();
    let local_normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(Iterator::collect);
    if let Some(n) = &local_normals {
        per_vertex("normals", n.len())?;
    }
    let normals = local_normals.as_ref().map(|n| {
        n.iter()
            .map(|&n| (normal_matrix * Vec3::from_array(n)).normalize_or_zero().to_array())
            .collect()
    });
    let uvs = match reader.read_tex_coords(uv_set) {
        Some(t) => {
            let t: Vec<[f32; 2]> = t.into_f32().collect();
            per_vertex("texture coordinates", t.len())?;
            Some(t)
        }
        None => None,
    };
    let flat: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..vertices as u32).collect(),
    };
    if let Some(&bad) = flat.iter().find(|&&i| i as usize >= vertices) {
        return Err(format!("indexes vertex {bad} of {vertices}"));
    }
    let mut indices: Vec<[u32; 3]> = flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let mut tangents = None;
    if material.normal_mapped {
        let mesh = LocalMesh {
            positions: &local_positions,
            indices: &indices,
            uvs: uvs.as_deref(),
            normals: local_normals.as_deref(),
            tangents: reader.read_tangents().map(Iterator::collect),
        };
        tangents = Some(corner_tangents(&mesh, transform)?);
    }
    // A mirroring transform flips the winding; keep triangles facing as authored.
    if transform.determinant() < 0.0 {
        indices.iter_mut().for_each(|t| t.swap(1, 2));
        tangents.iter_mut().flatten().for_each(|t| t.swap(1, 2));
    }
    Ok(Some(MeshData {
        positions,
        indices,
        uvs,
        normals,
        tangents,
    }))
}

/// A primitive's triangles in the mesh's own space, as tangents are made.
struct LocalMesh<'a> {
    positions: &'a [[f32; 3]],
    indices: &'a [[u32; 3]],
    uvs: Option<&'a [[f32; 2]]>,
    normals: Option<&'a [[f32; 3]]>,
    tangents: Option<Vec<[f32; 4]>>,
}

/// The tangents of each triangle's corners in world space (`transform`): the file's TANGENT
/// where the primitive has normals (glTF ignores it without), else MikkTSpace's of the
/// normal map's texture coordinates. A tangent turns with `transform`; its handedness
/// flips with a mirroring one.
fn corner_tangents(mesh: &LocalMesh, transform: Mat4) -> Result<Vec<CornerTangents>, String> {
    let local = match mesh.tangents.as_ref().filter(|_| mesh.normals.is_some()) {
        Some(t) => {
            if t.len() != mesh.positions.len() {
                return Err(format!("{} tangents for {} vertices", t.len(), mesh.positions.len()));
            }
            if let Some(i) = t.iter().position(|t| !t.iter().all(|c| c.is_finite())) {
                return Err(format!("tangent {i} is {:?}, not finite", t[i]));
            }
            mesh.indices.iter().map(|tri| tri.map(|i| t[i as usize])).collect()
        }
        None => {
            let zeros = vec![[0.0; 2]; mesh.positions.len()];
            tangents::generate(mesh.positions, mesh.indices, mesh.uvs.unwrap_or(&zeros), mesh.normals)?
        }
    };
    let matrix = glam::Mat3::from_mat4(transform);
    let handedness = transform.determinant().signum();
    Ok(local
        .into_iter()
        .map(|corners| {
            corners.map(|t| {
                let [x, y, z] = (matrix * Vec3::new(t[0], t[1], t[2])).normalize_or_zero().to_array();
                [x, y, z, if t[3] < 0.0 { -handedness } else { handedness }]
            })
        })
        .collect())
}

/// The perspective cameras of the document that a node of the scene holds, placed by the
/// first such node: glTF cameras look down their local -Z with +Y up.
fn cameras(document: &gltf::Document, nodes: &[Option<(Option<String>, Mat4)>]) -> Vec<ImportedCamera> {
    let mut out = Vec::new();
    for camera in document.cameras() {
        let Some((node_name, transform)) = &nodes[camera.index()] else {
            continue;
        };
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            continue;
        };
        let forward = transform.transform_vector3(Vec3::NEG_Z);
        let up = transform.transform_vector3(Vec3::Y);
        out.push(ImportedCamera {
            index: camera.index(),
            names: camera
                .name()
                .into_iter()
                .chain(node_name.as_deref())
                .map(String::from)
                .collect(),
            camera: Camera {
                position: transform.transform_point3(Vec3::ZERO).to_array(),
                look: Look::Forward(forward.to_array()),
                up: up.to_array(),
                fov_degrees: p.yfov().to_degrees(),
                fov_axis: FovAxis::Vertical,
                lens: None,
            },
            aspect_ratio: p.aspect_ratio(),
        });
    }
    out
}

/// How primitives use a material: its name, the emission its triangles give off as area
/// lights, the texture coordinate set its textures read, and whether it has a normal map
/// (its meshes then carry tangents).
#[derive(Clone)]
struct MaterialUse {
    name: String,
    emission: Rgb,
    uv_set: u32,
    normal_mapped: bool,
}

/// Turns glTF materials into [`Material`]s with [`Pbr`] parameters, and the images their
/// textures use into [`Texture`]s (each image once).
struct MaterialImport<'a> {
    images: &'a [gltf::image::Data],
    /// The texture made of each image, once one is.
    image_texture: Vec<Option<u32>>,
    out: &'a mut Imported,
}

impl MaterialImport<'_> {
    /// Adds material `m` to the output; returns how primitives use it.
    ///
    /// The area lights' radiance is the emissive factor (times its strength) alone: the
    /// emissive texture scales only the material's emission (`material_at`), so a light
    /// whose texture is mostly dark (DamagedHelmet) shines as if it were white. Applying the
    /// texture where lights are hit and sampled (and the texture's mean to the light's power
    /// estimate) belongs to the light code.
    fn material(&mut self, m: &gltf::Material) -> Result<MaterialUse, String> {
        let index = m.index().map_or_else(|| "default".to_string(), |i| format!("#{i}"));
        let name = format!("gltf:{}", m.name().map_or(index, String::from));
        let pbr = m.pbr_metallic_roughness();
        let factor = pbr.base_color_factor();
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = m.emissive_factor().map(|e| e * strength);
        let alpha_cutoff = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => None,
            gltf::material::AlphaMode::Mask => Some(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => {
                self.out.warnings.push(format!(
                    "material '{name}': alpha mode BLEND is rendered as MASK at 0.5"
                ));
                Some(0.5)
            }
        };
        let textures = PbrTextures {
            base_color: pbr.base_color_texture().map(|t| self.texture(&t)).transpose()?,
            metallic_roughness: pbr.metallic_roughness_texture().map(|t| self.texture(&t)).transpose()?,
            emissive: m.emissive_texture().map(|t| self.texture(&t)).transpose()?,
            normal: m.normal_texture().map(|t| self.normal_texture(&t)).transpose()?,
        };
        // One set of texture coordinates per mesh: the base colour's, else another slot's.
        let normal = textures.normal.map(|n| n.texture);
        let slots = [
            &textures.base_color,
            &textures.metallic_roughness,
            &textures.emissive,
            &normal,
        ];
        let sets: Vec<u32> = slots.iter().filter_map(|t| t.map(|t| t.tex_coord)).collect();
        let uv_set = sets.first().copied().unwrap_or(0);
        if sets.iter().any(|&s| s != uv_set) {
            self.out.warnings.push(format!(
                "material '{name}': its textures read texture coordinate sets {sets:?}; all read set {uv_set}"
            ));
        }
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
        let ior = self.specular_ior(&name, m, m.ior().unwrap_or(1.5), transmission);
        let thin_walled = self.thin_walled(m, transmission);
        let interior = if transmission > 0.0 && !thin_walled {
            self.attenuation(&name, m)?
        } else {
            None
        };
        self.out.materials.insert(
            name.clone(),
            Material {
                interior,
                two_sided: m.double_sided(),
                pbr: Some(Pbr {
                    base_color: [factor[0], factor[1], factor[2]],
                    alpha: factor[3],
                    alpha_cutoff,
                    metallic: pbr.metallic_factor(),
                    roughness: pbr.roughness_factor(),
                    transmission,
                    ior,
                    thin_walled,
                    emission,
                    textures,
                    ..Default::default()
                }),
                ..Default::default()
            },
        );
        Ok(MaterialUse {
            name,
            emission,
            uv_set,
            normal_mapped: normal.is_some(),
        })
    }

    /// The index of refraction that renders KHR_materials_specular's strength and colour of
    /// the dielectric specular layer: its reflectance at normal incidence
    /// specular x min(F0(ior) x luminance(specular colour), 1), the extension's, through the
    /// Fresnel curve of another index (specular 0, the pure Lambertian of Mitsuba's diffuse
    /// in Bitterli's conversions, gives index 1: no layer). Approximations, each warned: a
    /// coloured specular is rendered as its luminance, the textures are not read (their
    /// factors are), and transmissive materials keep their index (it also bends their light).
    fn specular_ior(&mut self, name: &str, m: &gltf::Material, ior: f32, transmission: f32) -> f32 {
        let Some(s) = m.specular() else { return ior };
        let (factor, color) = (s.specular_factor(), s.specular_color_factor());
        if s.specular_texture().is_some() || s.specular_color_texture().is_some() {
            self.out.warnings.push(format!(
                "material '{name}': KHR_materials_specular's textures are not read (their factors are)"
            ));
        }
        if factor == 1.0 && color == [1.0; 3] {
            return ior;
        }
        if transmission > 0.0 {
            self.out.warnings.push(format!(
                "material '{name}': KHR_materials_specular on a transmissive material is not rendered (its index of refraction stays {ior})"
            ));
            return ior;
        }
        let spread = color.iter().fold(f32::MIN, |a, &b| a.max(b)) - color.iter().fold(f32::MAX, |a, &b| a.min(b));
        if spread > 1e-3 {
            self.out.warnings.push(format!(
                "material '{name}': KHR_materials_specular's colour {color:?} is rendered as its luminance"
            ));
        }
        let luminance = crate::model::luminance(color) as f32;
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        ior_of_reflectance((factor * (f0 * luminance).min(1.0)).clamp(0.0, 0.99))
    }

    /// Whether transmissive material `m` is thin-walled: glTF's transmission without
    /// KHR_materials_volume, or with thickness 0, passes through an infinitely thin sheet; a
    /// positive thickness makes the mesh the boundary of a solid volume, which refracts. The
    /// thickness's value and texture serve renderers that do not trace the volume's geometry
    /// (lightgraph does).
    fn thin_walled(&self, m: &gltf::Material, transmission: f32) -> bool {
        transmission > 0.0 && m.volume().is_none_or(|v| v.thickness_factor() <= 0.0)
    }

    /// The medium inside the solid volume of material `name` (named after it; the material's
    /// `interior`): KHR_materials_volume's Beer-Lambert attenuation, light of colour c left
    /// after distance d, as the absorption coefficient -ln(c) / d, without scattering (a
    /// channel of colour 0, which absorbs everything, as -ln(1e-6) / d). None for a white
    /// colour or an infinite distance (the defaults): a clear volume. A colour outside [0, 1]
    /// or a distance that is not positive is an error.
    fn attenuation(&mut self, name: &str, m: &gltf::Material) -> Result<Option<String>, String> {
        let Some(volume) = m.volume() else { return Ok(None) };
        let (color, distance) = (volume.attenuation_color(), volume.attenuation_distance());
        if color.iter().any(|c| !(0.0..=1.0).contains(c)) || distance.is_nan() || distance <= 0.0 {
            return Err(format!(
                "material '{name}': KHR_materials_volume's attenuationColor {color:?} must lie in [0, 1] and its attenuationDistance {distance} be positive"
            ));
        }
        if distance.is_infinite() || color == [1.0; 3] {
            return Ok(None);
        }
        let sigma_a = color.map(|c| -c.max(1e-6).ln() / distance);
        self.out.media.insert(
            name.to_string(),
            Medium {
                sigma_a,
                sigma_s: [0.0; 3],
                scale: 1.0,
                phase: Default::default(),
                grid: None,
            },
        );
        Ok(Some(name.to_string()))
    }

    /// The reference a material slot makes to a texture, converting its image on first use.
    fn texture(&mut self, info: &gltf::texture::Info) -> Result<TextureRef, String> {
        let mut r = self.texture_ref(&info.texture(), info.tex_coord())?;
        if let Some(t) = info.texture_transform() {
            r.transform = uv_transform(t.offset(), t.scale(), t.rotation());
            r.tex_coord = t.tex_coord().unwrap_or(r.tex_coord);
        }
        Ok(r)
    }

    /// The normal map of a material (the `gltf` crate reads no KHR_texture_transform of
    /// it: read here from its JSON).
    fn normal_texture(&mut self, n: &gltf::material::NormalTexture) -> Result<NormalTexture, String> {
        let mut texture = self.texture_ref(&n.texture(), n.tex_coord())?;
        if let Some(t) = n.extension_value("KHR_texture_transform") {
            let pair = |key: &str, default: f32| -> [f32; 2] {
                let v = |i: usize| t[key][i].as_f64().map_or(default, |x| x as f32);
                [v(0), v(1)]
            };
            let rotation = t["rotation"].as_f64().unwrap_or(0.0) as f32;
            texture.transform = uv_transform(pair("offset", 0.0), pair("scale", 1.0), rotation);
            texture.tex_coord = t["texCoord"].as_u64().map_or(texture.tex_coord, |c| c as u32);
        }
        Ok(NormalTexture {
            texture,
            scale: n.scale(),
        })
    }

    /// The reference to `texture` read at texture coordinate set `tex_coord`, converting its
    /// image on first use.
    fn texture_ref(&mut self, texture: &gltf::Texture, tex_coord: u32) -> Result<TextureRef, String> {
        let image = texture.source().index();
        let data = self
            .images
            .get(image)
            .ok_or_else(|| format!("texture {} uses image {image}, which was not loaded", texture.index()))?;
        let index = match self.image_texture[image] {
            Some(i) => i,
            None => {
                let name = texture
                    .source()
                    .name()
                    .map_or_else(|| format!("image {image}"), String::from);
                let converted = rgba8(data, &name)?;
                self.out.textures.push(converted);
                let i = self.out.textures.len() as u32 - 1;
                self.image_texture[image] = Some(i);
                i
            }
        };
        let wrap = |mode| match mode {
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let sampler = texture.sampler();
        let mut r = TextureRef::new(index);
        r.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        r.tex_coord = tex_coord;
        Ok(r)
    }
}

/// KHR_texture_transform's matrix: translation x rotation x scale, rotating counter-clockwise
/// in uv.
fn uv_transform([ox, oy]: [f32; 2], [sx, sy]: [f32; 2], rotation: f32) -> [[f32; 3]; 2] {
    let (sin, cos) = rotation.sin_cos();
    [[cos * sx, sin * sy, ox], [-sin * sx, cos * sy, oy]]
}

/// An image as RGBA8 texels (grey fills R, G and B; missing alpha is opaque; 16-bit and float
/// channels are rounded to 8 bits, floats clamped to [0, 1]).
fn rgba8(image: &gltf::image::Data, name: &str) -> Result<Texture, String> {
    use gltf::image::Format;
    let (channels, bytes) = match image.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.pixels.len() != w * h * channels * bytes {
        return Err(format!(
            "{name}: {} bytes of pixels for {w}x{h} texels of {channels} channels",
            image.pixels.len()
        ));
    }
    let channel = |c: &[u8]| -> u32 {
        match bytes {
            1 => c[0] as u32,
            2 => u16::from_ne_bytes([c[0], c[1]]) as u32 >> 8,
            _ => (f32::from_ne_bytes([c[0], c[1], c[2], c[3]]).clamp(0.0, 1.0) * 255.0).round() as u32,
        }
    };
    let texels = image
        .pixels
        .chunks_exact(channels * bytes)
        .map(|px| {
            let v: Vec<u32> = px.chunks_exact(bytes).map(channel).collect();
            let (rgb, a) = match channels {
                1 => ([v[0]; 3], 255),
                2 => ([v[0]; 3], v[1]),
                3 => ([v[0], v[1], v[2]], 255),
                _ => ([v[0], v[1], v[2]], v[3]),
            };
            rgb[0] | rgb[1] << 8 | rgb[2] << 16 | a << 24
        })
        .collect();
    Ok(Texture {
        name: name.to_string(),
        width: image.width,
        height: image.height,
        texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{Value, json};

    /// Imports the committed glTF Cornell box after `edit` of its JSON and buffer, from a
    /// temporary directory named after `test`.
    fn import_edited(test: &str, edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Result<Imported, String> {
        let from = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/gltf/cornell_box");
        let mut doc: Value =
            serde_json::from_slice(&std::fs::read(from.join("CornellBox-Original.gltf")).unwrap()).unwrap();
        let mut bin = std::fs::read(from.join("CornellBox-Original.bin")).unwrap();
        edit(&mut doc, &mut bin);
        let dir = std::env::temp_dir().join(format!("lightgraph-gltf-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("CornellBox-Original.gltf"), doc.to_string()).unwrap();
        std::fs::write(dir.join("CornellBox-Original.bin"), bin).unwrap();
        let result = import(&dir.join("CornellBox-Original.gltf"));
        std::fs::remove_dir_all(dir).unwrap();
        result
    }

    fn error(test: &str, edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> String {
        import_edited(test, edit).map(|_| ()).expect_err("the asset is refused")
    }

    #[test]
    fn the_unedited_asset_loads() {
        assert_eq!(import_edited("unedited", |_, _| {}).unwrap().triangles, 36);
    }

    /// The first material of the Cornell box ('floor') with `extensions` added, and the
    /// warnings.
    fn with_material_extensions(test: &str, extensions: Value) -> (Pbr, Vec<String>) {
        let imported = import_edited(test, |doc, _| {
            doc["materials"][0]["extensions"] = extensions;
            doc["extensionsUsed"] = json!([
                "KHR_materials_specular",
                "KHR_materials_ior",
                "KHR_materials_transmission",
                "KHR_materials_volume",
                "KHR_materials_sheen"
            ]);
        })
        .unwrap();
        let pbr = imported.materials["gltf:floor"].pbr.clone().unwrap();
        (pbr, imported.warnings)
    }

    /// Normal-incidence reflectance of a dielectric of index `ior`.
    fn f0(ior: f32) -> f32 {
        ((ior - 1.0) / (ior + 1.0)).powi(2)
    }

    #[test]
    fn khr_materials_specular_scales_the_specular_layer_through_the_index() {
        // Specular 0: no layer (Mitsuba's pure Lambertian in Bitterli's conversions).
        let (p, warnings) =
            with_material_extensions("specular-0", json!({"KHR_materials_specular": {"specularFactor": 0.0}}));
        assert_eq!(p.ior, 1.0);
        assert!(
            warnings.iter().any(|w| w.contains("KHR_materials_sheen")),
            "{warnings:?}"
        );
        assert!(
            !warnings.iter().any(|w| w.contains("KHR_materials_specular")),
            "{warnings:?}"
        );
        // Half strength at index 1.5: half its reflectance.
        let (p, _) = with_material_extensions(
            "specular-half",
            json!({"KHR_materials_specular": {"specularFactor": 0.5}}),
        );
        assert!((f0(p.ior) - 0.5 * f0(1.5)).abs() < 1e-6, "{}", p.ior);
        // A grey colour scales like the factor; with the index's own extension.
        let (p, _) = with_material_extensions(
            "specular-colour",
            json!({"KHR_materials_specular": {"specularColorFactor": [2.0, 2.0, 2.0]}, "KHR_materials_ior": {"ior": 1.4}}),
        );
        assert!((f0(p.ior) - 2.0 * f0(1.4)).abs() < 1e-6, "{}", p.ior);
        // A coloured one is its luminance, with a warning; full strength keeps the index.
        let (_, warnings) = with_material_extensions(
            "specular-tint",
            json!({"KHR_materials_specular": {"specularColorFactor": [1.0, 0.5, 0.5]}}),
        );
        assert!(warnings.iter().any(|w| w.contains("luminance")), "{warnings:?}");
        let (p, _) = with_material_extensions("specular-1", json!({"KHR_materials_specular": {"specularFactor": 1.0}}));
        assert_eq!(p.ior, 1.5);
    }

    #[test]
    fn transmission_is_thin_walled_unless_a_volume_has_thickness() {
        let transmission = json!({"transmissionFactor": 1.0});
        let thin = |extensions: Value| {
            let (p, warnings) = with_material_extensions("volume", extensions);
            assert!(
                !warnings.iter().any(|w| w.contains("KHR_materials_volume")),
                "{warnings:?}"
            );
            p.thin_walled
        };
        // glTF: without KHR_materials_volume, or with thickness 0 (its default), thin-walled.
        assert!(thin(json!({"KHR_materials_transmission": transmission})));
        assert!(thin(
            json!({"KHR_materials_transmission": transmission, "KHR_materials_volume": {"thicknessFactor": 0.0}})
        ));
        assert!(thin(
            json!({"KHR_materials_transmission": transmission, "KHR_materials_volume": {}})
        ));
        // A positive thickness: the surface of a solid volume.
        let solid =
            json!({"KHR_materials_transmission": transmission, "KHR_materials_volume": {"thicknessFactor": 0.5}});
        assert!(!thin(solid));
        // No transmission: neither (the flag is transmission's).
        assert!(!thin(json!({})));
        assert!(!thin(json!({"KHR_materials_volume": {"thicknessFactor": 0.0}})));
    }

    /// The interior medium of the Cornell box's first material ('floor') made a transmissive
    /// volume of thickness 0.1 with `attenuation`, and the media imported.
    fn volume_medium(test: &str, attenuation: Value) -> Result<(Option<String>, BTreeMap<String, Medium>), String> {
        let mut v = json!({"thicknessFactor": 0.1});
        v.as_object_mut()
            .unwrap()
            .extend(attenuation.as_object().unwrap().clone());
        let imported = import_edited(test, |doc, _| {
            doc["materials"][0]["extensions"] =
                json!({"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_volume": v});
            doc["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
        })?;
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
        Ok((imported.materials["gltf:floor"].interior.clone(), imported.media))
    }

    #[test]
    fn a_volume_attenuation_is_an_absorbing_medium_inside_named_after_the_material() {
        let (interior, media) = volume_medium(
            "attenuation",
            json!({"attenuationColor": [0.5, 0.25, 1.0], "attenuationDistance": 0.2}),
        )
        .unwrap();
        assert_eq!(interior.as_deref(), Some("gltf:floor"));
        let m = &media["gltf:floor"];
        // Light of colour c is left after the distance: exp(-sigma_a d) = c.
        let left: Vec<f32> = m.sigma_a.iter().map(|s| (-s * 0.2).exp()).collect();
        assert!(
            left.iter().zip([0.5, 0.25, 1.0]).all(|(l, c)| (l - c).abs() < 1e-6),
            "{left:?}"
        );
        assert_eq!((m.sigma_s, m.scale), ([0.0; 3], 1.0));
        // No absorption: a white colour, or an infinite distance (the defaults).
        for (test, attenuation) in [
            ("attenuation-white", json!({"attenuationDistance": 0.2})),
            ("attenuation-far", json!({"attenuationColor": [0.5, 0.8, 1.0]})),
        ] {
            let (interior, media) = volume_medium(test, attenuation).unwrap();
            assert!(interior.is_none() && media.is_empty(), "{test}");
        }
        let e = volume_medium(
            "attenuation-bad",
            json!({"attenuationColor": [1.5, 0.8, 1.0], "attenuationDistance": 1.0}),
        )
        .unwrap_err();
        assert!(
            e.contains(
                "material 'gltf:floor': KHR_materials_volume's attenuationColor [1.5, 0.8, 1.0] must lie in [0, 1]"
            ),
            "{e}"
        );
    }

    /// Writes a glTF of one tetrahedron (the first `faces` of its four, each face with
    /// vertices of its own) of a transmissive material with an attenuating volume; returns
    /// its path.
    fn tetrahedron(test: &str, faces: usize) -> std::path::PathBuf {
        let p = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let corners = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let bytes: Vec<u8> = corners[..faces]
            .iter()
            .flatten()
            .flat_map(|&i| p[i])
            .flat_map(f32::to_le_bytes)
            .collect();
        let doc = json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume"],
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "materials": [{"name": "glass", "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1.0}
            }}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": faces * 3, "type": "VEC3",
                           "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]}],
            "bufferViews": [{"buffer": 0, "byteLength": bytes.len()}],
            "buffers": [{"uri": "t.bin", "byteLength": bytes.len()}]
        });
        let dir = std::env::temp_dir().join(format!("lightgraph-gltf-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("t.bin"), bytes).unwrap();
        std::fs::write(dir.join("t.gltf"), doc.to_string()).unwrap();
        dir.join("t.gltf")
    }

    #[test]
    fn a_volume_must_be_closed_by_position_though_its_vertices_are_split() {
        let closed = tetrahedron("closed-volume", 4);
        let (scene, _) = crate::resolve::scene_from_gltf(&closed).unwrap();
        std::fs::remove_dir_all(closed.parent().unwrap()).unwrap();
        assert_eq!(scene.materials["gltf:glass"].interior.as_deref(), Some("gltf:glass"));
        assert!(scene.media.contains_key("gltf:glass"));
        let open = tetrahedron("open-volume", 3);
        let e = crate::resolve::scene_from_gltf(&open).unwrap_err().to_string();
        std::fs::remove_dir_all(open.parent().unwrap()).unwrap();
        assert!(
            e.contains("medium 'gltf:glass' is not enclosed")
                && e.contains("material 'gltf:glass' has it as its interior"),
            "{e}"
        );
    }

    #[test]
    fn a_uri_that_does_not_decode_to_utf8_is_an_error() {
        let e = error("uri", |doc, _| doc["buffers"][0]["uri"] = json!("%FF.bin"));
        assert!(
            e.ends_with("buffer 0: URI '%FF.bin' does not percent-decode to UTF-8"),
            "{e}"
        );
        assert!(percent_decodes("a%20b%C3%A9%zz%"));
    }

    #[test]
    fn an_image_without_a_source_or_mime_type_is_an_error() {
        let e = error("image-mime", |doc, _| doc["images"] = json!([{"bufferView": 0}]));
        assert!(e.ends_with("image 0 has a bufferView but no mimeType"), "{e}");
        let e = error("image-source", |doc, _| doc["images"] = json!([{"name": "x"}]));
        assert!(e.ends_with("image 0 has neither a uri nor a bufferView"), "{e}");
    }

    #[test]
    fn a_buffer_view_beyond_its_buffer_is_an_error() {
        let e = error("view", |doc, _| {
            doc["images"] = json!([{"bufferView": 0, "mimeType": "image/png"}]);
            doc["bufferViews"][0]["byteLength"] = json!(1_000_000);
        });
        assert!(
            e.ends_with("buffer view 0 (bytes 0..+1000000) lies beyond its buffer 0 of 2592 bytes"),
            "{e}"
        );
    }

    #[test]
    fn accessors_gltf_cannot_read_are_errors() {
        let accessor = |doc: &mut Value, field: &str, value: Value| doc["accessors"][0][field] = value;
        let huge = |doc: &mut Value, _: &mut Vec<u8>| accessor(doc, "count", json!(1u64 << 31));
        let e = error("count", huge);
        assert!(e.contains("accessor 0: 2147483648 elements of 12 bytes every 12 bytes from byte 0 do not fit its buffer view 0 of 72 bytes"), "{e}");
        let e = error("sparse", |doc, _| {
            accessor(
                doc,
                "sparse",
                json!({"count": 1u64 << 31, "indices": {"bufferView": 1, "componentType": 5125}, "values": {"bufferView": 1}}),
            );
            doc["accessors"][0].as_object_mut().unwrap().remove("bufferView");
        });
        assert!(e.contains("accessor 0 is sparse"), "{e}");
        let e = error("type", |doc, _| accessor(doc, "type", json!("VEC2")));
        assert!(
            e.contains("accessor 0 holds Vec2 of F32; expected Vec3 of [F32]"),
            "{e}"
        );
        let e = error("indices", |doc, _| {
            doc["meshes"][0]["primitives"][0]["indices"] = json!(1)
        });
        assert!(
            e.contains("accessor 1 holds Vec3 of F32; expected Scalar of [U8, U16, U32]"),
            "{e}"
        );
        let e = error("stride", |doc, _| doc["bufferViews"][0]["byteStride"] = json!(8));
        assert!(e.contains("accessor 0 has 6 elements of 12 bytes every 8 bytes"), "{e}");
        let e = error("empty", |doc, _| accessor(doc, "count", json!(0)));
        assert!(e.contains("accessor 0 has 0 elements"), "{e}");
    }

    #[test]
    fn a_cycle_of_nodes_is_an_error() {
        let e = error("cycle", |doc, _| doc["nodes"][0]["children"] = json!([0]));
        assert!(
            e.ends_with("node 0 is reached twice from the scene (a cycle, or two parents)"),
            "{e}"
        );
    }

    #[test]
    fn position_accessor_out_of_range_is_an_error() {
        let e = error("position", |doc, _| {
            doc["meshes"][0]["primitives"][1]["attributes"]["POSITION"] = json!(5126);
        });
        assert!(
            e.ends_with(
                "CornellBox-Original.gltf: mesh 0, primitive 1: attribute POSITION uses accessor 5126, but there are 16"
            ),
            "{e}"
        );
    }
}
