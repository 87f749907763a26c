//! A scene's shapes and lights flattened into what the GPU reads: primitives (triangles and
//! spheres) with their vertex attributes and area lights, then the scene's other lights.

use crate::gpu::{
    self, GpuEnvironment, GpuLight, GpuPrimitive, GpuTriangleAttributes, attribute_flags, light_kind, primitive_kind,
};
use crate::model::environment::{self, TexelLayout};
use crate::model::{self, Light, Scene, Shape, SpotFalloff};
use bytemuck::Zeroable;
use glam::Vec3;
use std::collections::BTreeMap;

/// The largest coordinate (or sphere radius) a shape may have: as far as a ray travels
/// (`INFINITE_DISTANCE` in the WGSL).
pub const MAX_COORDINATE: f32 = 1e30;

/// The primitives of a scene's shapes in shape order (quads as two triangles, meshes as their
/// triangles), the area lights of the emissive triangles, and the vertex attributes of each
/// primitive (`None` when no mesh has texture coordinates, normals or tangents), and the
/// tangent entries of the normal-mapped triangles, which their attributes index from 0
/// ([`append_tangents`] places them).
pub(crate) struct Geometry {
    pub primitives: Vec<GpuPrimitive>,
    pub lights: Vec<GpuLight>,
    pub attributes: Option<Vec<GpuTriangleAttributes>>,
    pub tangents: Vec<GpuTriangleAttributes>,
}

/// The scene's shapes flattened, each checked first ([`check_shape`]); `material_index` maps a
/// material's name to its index.
pub(crate) fn flatten_shapes(scene: &Scene, material_index: &BTreeMap<&str, u32>) -> Result<Geometry, String> {
    let with_attributes = scene
        .shapes
        .iter()
        .any(|s| matches!(s, Shape::Mesh { uvs, normals, tangents, .. } if uvs.is_some() || normals.is_some() || tangents.is_some()));
    let mut g = Geometry {
        primitives: Vec::new(),
        lights: Vec::new(),
        attributes: with_attributes.then(Vec::new),
        tangents: Vec::new(),
    };
    for (s, shape) in scene.shapes.iter().enumerate() {
        check_shape(s, shape)?;
        match shape {
            Shape::Triangle {
                vertices,
                material,
                emission,
            } => {
                g.push_triangle(vertices.map(v3), material_index[material.as_str()], *emission);
            }
            Shape::Quad {
                corners,
                material,
                emission,
            } => {
                let c = corners.map(v3);
                let m = material_index[material.as_str()];
                g.push_triangle([c[0], c[1], c[2]], m, *emission);
                g.push_triangle([c[0], c[2], c[3]], m, *emission);
            }
            Shape::Mesh {
                positions,
                indices,
                material,
                emission,
                uvs,
                normals,
                tangents,
            } => {
                let m = material_index[material.as_str()];
                let textures = scene.materials[material.as_str()].pbr.as_ref().map(|p| &p.textures);
                let emissive_texture = textures.and_then(|t| t.emissive);
                // Tangents only where the material has a normal map.
                let normal_scale = textures.and_then(|t| t.normal).map(|n| n.scale);
                for (k, t) in indices.iter().enumerate() {
                    // An emissive texture scales the light by its mean over the triangle.
                    let emission = match (emission, emissive_texture, uvs) {
                        (Some(e), Some(r), Some(uv)) => {
                            let mean = r.mean_over_triangle(&scene.textures, t.map(|i| uv[i as usize]), true);
                            Some(std::array::from_fn(|c| e[c] * mean[c]))
                        }
                        _ => *emission,
                    };
                    let corners = t.map(|i| v3(positions[i as usize]));
                    let emits = g.push_triangle(corners, m, emission);
                    let Some(a) = &mut g.attributes else { continue };
                    // Emitters are shaded with their geometric normal (the lights' own).
                    let normals = normals.as_deref().filter(|_| !emits);
                    let mut attributes = triangle_attributes(*t, corners, uvs.as_deref(), normals);
                    if let (Some(scale), Some(tangents), false) = (normal_scale, tangents, emits) {
                        attributes.flags |= tangents_index(g.tangents.len())?;
                        g.tangents.push(GpuTriangleAttributes::tangents(tangents[k], scale));
                    }
                    a.push(attributes);
                }
            }
            Shape::Sphere {
                center,
                radius,
                material,
            } => g.primitives.push(GpuPrimitive {
                a: *center,
                material: material_index[material.as_str()],
                b: [*radius, 0.0, 0.0],
                light: -1,
                c: [0.0; 3],
                kind: primitive_kind::SPHERE,
            }),
        }
        if let Some(a) = &mut g.attributes {
            a.resize(g.primitives.len(), GpuTriangleAttributes::default());
        }
    }
    Ok(g)
}

impl Geometry {
    /// A triangle of material `material`, and its area light where `emission` is not black
    /// (then true).
    fn push_triangle(&mut self, v: [Vec3; 3], material: u32, emission: Option<[f32; 3]>) -> bool {
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let light = match emission {
            Some(radiance) if radiance.iter().any(|&c| c > 0.0) => {
                self.lights.push(area_light(v[0], e1, e2, radiance));
                self.lights.len() as i32 - 1
            }
            _ => -1,
        };
        self.primitives.push(GpuPrimitive {
            a: v[0].into(),
            material,
            b: e1.into(),
            light,
            c: e2.into(),
            kind: primitive_kind::TRIANGLE,
        });
        light >= 0
    }
}

/// The area light of the triangle v0, v0 + e1, v0 + e2 emitting `radiance` on its front side.
fn area_light(v0: Vec3, e1: Vec3, e2: Vec3, radiance: [f32; 3]) -> GpuLight {
    let cross = e1.cross(e2);
    let area = 0.5 * cross.length();
    GpuLight {
        position: v0.into(),
        kind: light_kind::AREA,
        e1: e1.into(),
        inv_area: if area > 0.0 { 1.0 / area } else { 0.0 },
        e2: e2.into(),
        cos_inner: 0.0,
        normal: cross.normalize_or_zero().into(),
        cos_outer: 0.0,
        radiance,
        pad2: 0.0,
    }
}

/// What a scene's Background or Environment light adds besides its [`GpuLight`]: its index in
/// the lights (-1 without one), the environment map's size and rotation and its sampling
/// distribution (none without a map).
pub(crate) struct Sky {
    pub background: i32,
    pub environment: GpuEnvironment,
    pub distribution: Option<environment::Distribution>,
}

/// Appends the scene's lights (`lights`, after the area lights already in `out`).
pub(crate) fn push_scene_lights(lights: &[Light], out: &mut Vec<GpuLight>) -> Result<Sky, String> {
    let mut sky = Sky {
        background: -1,
        environment: GpuEnvironment::zeroed(),
        distribution: None,
    };
    for light in lights {
        let mut l = GpuLight::zeroed();
        match light {
            Light::Point { position, intensity } => {
                l.kind = light_kind::POINT;
                l.position = *position;
                l.radiance = *intensity;
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_cone_degrees,
                outer_cone_degrees,
                falloff,
            } => {
                l.kind = light_kind::SPOT;
                l.e2[0] = match falloff {
                    SpotFalloff::Smooth => 0.0,
                    SpotFalloff::Linear => 1.0,
                };
                l.position = *position;
                l.e1 = v3(*direction).normalize_or_zero().into();
                l.radiance = *intensity;
                l.cos_inner = inner_cone_degrees.to_radians().cos();
                l.cos_outer = outer_cone_degrees.to_radians().cos();
            }
            Light::Directional { direction, irradiance } => {
                l.kind = light_kind::DIRECTIONAL;
                l.position = v3(*direction).normalize_or_zero().into();
                l.radiance = *irradiance;
            }
            Light::Background { radiance, scale } => {
                l.kind = light_kind::BACKGROUND;
                l.radiance = radiance.map(|c| c * scale);
                sky.background = out.len() as i32;
            }
            Light::Environment {
                file,
                scale,
                rotation_degrees,
                layout,
                map,
            } => {
                let map = map.as_ref().ok_or_else(|| {
                    format!("environment map '{file}' was not loaded (resolve the scene's assets first)")
                })?;
                l.kind = light_kind::ENVIRONMENT;
                l.radiance = [*scale; 3];
                sky.background = out.len() as i32;
                let (sin, cos) = rotation_degrees.to_radians().sin_cos();
                sky.environment = GpuEnvironment {
                    width: map.width,
                    height: map.height,
                    cos_rotation: cos,
                    sin_rotation: sin,
                    pole_to_pole: (*layout == TexelLayout::PoleToPole) as u32,
                };
                sky.distribution = Some(map.distribution(*layout));
            }
        }
        out.push(l);
    }
    Ok(sky)
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// The attribute flags of a triangle whose tangents are attributes entry `index`.
fn tangents_index(index: usize) -> Result<u32, String> {
    u32::try_from(index)
        .ok()
        .filter(|&i| i < 1 << (32 - attribute_flags::TANGENTS_SHIFT))
        .map(|i| attribute_flags::TANGENTS | i << attribute_flags::TANGENTS_SHIFT)
        .ok_or_else(|| format!("{index} attributes entries: tangents past 2^30 cannot be indexed"))
}

/// Appends the `tangents` entries to the `attributes` of the primitives (in any order), and
/// points the normal-mapped triangles' flags at them.
pub(crate) fn append_tangents(
    attributes: &mut Vec<GpuTriangleAttributes>,
    tangents: Vec<GpuTriangleAttributes>,
) -> Result<(), String> {
    let first = attributes.len();
    tangents_index(first + tangents.len())?;
    for a in attributes
        .iter_mut()
        .filter(|a| a.flags & attribute_flags::TANGENTS != 0)
    {
        let index = (a.flags >> attribute_flags::TANGENTS_SHIFT) as usize + first;
        a.flags = a.flags & !(u32::MAX << attribute_flags::TANGENTS_SHIFT) | tangents_index(index)?;
    }
    attributes.extend(tangents);
    Ok(())
}

/// The sine of the largest angle between a vertex normal and the geometric normal (either
/// facing) at which a triangle still counts as flat (its vertex normals dropped): 1e-4
/// radians, about the precision of the normals' octahedral encoding.
const FLAT_SIN: f32 = 1e-4;

/// The attributes of mesh triangle `t` with corners `corners`: its vertices' texture
/// coordinates ((0, 0) without), and their normals when all three are finite and non-zero
/// and one of them differs from the triangle's geometric normal (else the geometric normal
/// shades it: no scene pays for shading normals that change nothing).
fn triangle_attributes(
    t: [u32; 3],
    corners: [Vec3; 3],
    uvs: Option<&[[f32; 2]]>,
    normals: Option<&[model::Vec3]>,
) -> GpuTriangleAttributes {
    let uv = |i: u32| uvs.map_or([0.0; 2], |u| u[i as usize]);
    let mut a = GpuTriangleAttributes {
        uv0: uv(t[0]),
        uv1: uv(t[1]),
        uv2: uv(t[2]),
        ..Default::default()
    };
    if let Some(n) = normals {
        let n = t.map(|i| v3(n[i as usize]));
        let ng = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let flat = n.iter().all(|n| n.normalize_or_zero().cross(ng).length() <= FLAT_SIN);
        if !flat && n.iter().all(|n| n.is_finite() && n.length_squared() > 0.0) {
            [a.n0, a.n1, a.n2] = n.map(|n| gpu::encode_octahedral(n.normalize().to_array()));
            a.flags = gpu::attribute_flags::NORMALS;
        }
    }
    a
}

/// Checks what flattening needs of shape `index`: mesh indices within its vertices, as many
/// texture coordinates and normals as vertices, finite coordinates within [`MAX_COORDINATE`].
fn check_shape(index: usize, shape: &Shape) -> Result<(), String> {
    let (points, radius): (&[model::Vec3], Option<&f32>) = match shape {
        Shape::Triangle { vertices, .. } => (vertices, None),
        Shape::Quad { corners, .. } => (corners, None),
        Shape::Mesh { positions, .. } => (positions, None),
        Shape::Sphere { center, radius, .. } => (std::slice::from_ref(center), Some(radius)),
    };
    if let Some(v) = points
        .iter()
        .flatten()
        .chain(radius)
        .find(|v| !v.is_finite() || v.abs() > MAX_COORDINATE)
    {
        return Err(format!(
            "shape {index}: coordinate {v} is not a finite number within ±{MAX_COORDINATE:e}"
        ));
    }
    if let Shape::Mesh {
        positions,
        indices,
        uvs,
        normals,
        tangents,
        ..
    } = shape
    {
        if let Some(&i) = indices.iter().flatten().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "shape {index}: a mesh triangle uses vertex {i}, but the mesh has {} vertices",
                positions.len()
            ));
        }
        let counts = [
            ("uvs", uvs.as_ref().map(Vec::len)),
            ("normals", normals.as_ref().map(Vec::len)),
        ];
        if let Some((what, n)) = counts
            .iter()
            .find_map(|(w, n)| n.filter(|&n| n != positions.len()).map(|n| (w, n)))
        {
            return Err(format!(
                "shape {index}: the mesh has {n} {what} for {} vertices",
                positions.len()
            ));
        }
        if let Some(v) = uvs.iter().flatten().flatten().find(|v| !v.is_finite()) {
            return Err(format!("shape {index}: texture coordinate {v} is not a finite number"));
        }
        if let Some(t) = tangents.as_ref().filter(|t| t.len() != indices.len()) {
            return Err(format!(
                "shape {index}: the mesh has tangents for {} triangles of {}",
                t.len(),
                indices.len()
            ));
        }
        if let Some(v) = tangents.iter().flatten().flatten().flatten().find(|v| !v.is_finite()) {
            return Err(format!("shape {index}: tangent component {v} is not a finite number"));
        }
    }
    Ok(())
}
