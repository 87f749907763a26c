//! The scene compiled for the GPU: its shapes flattened into primitives and lights, a BVH over
//! them, its materials and textures packed, the light-selection table and the environment
//! map's distribution.

use super::materials::gpu_material;
use super::textures::PackedTextures;
use crate::build::acceleration::{build_bvh, traced_boxes};
use crate::build::bvh::BvhKind;
use crate::build::light_power::light_power;
use crate::build::{alias, flatten, plastic};
use crate::gpu::{
    GpuAliasEntry, GpuEnvironment, GpuLight, GpuMaterial, GpuPrimitive, GpuSceneInfo, GpuTextureInfo,
    GpuTriangleAttributes, material_flags, primitive_kind,
};
use crate::model::Scene;
use glam::Vec3A;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The scene flattened for the GPU, with its BVH.
#[derive(Debug, Clone)]
pub struct CompiledScene {
    /// Scene-wide values.
    pub info: GpuSceneInfo,
    /// Primitives in the leaf order of the BVH.
    pub primitives: Vec<GpuPrimitive>,
    /// The kind of BVH built.
    pub bvh_kind: BvhKind,
    /// The BVH's nodes as the GPU reads them: [`crate::gpu::GpuBvhNode`]s for [`BvhKind::Bvh2`],
    /// [`crate::gpu::GpuCwbvhNode`]s for [`BvhKind::Cwbvh`].
    pub bvh: Vec<u8>,
    /// `order[i]`: index (in shape order, quads counting as two triangles) of primitive `i`.
    pub order: Vec<u32>,
    /// Materials, in name order.
    pub materials: Vec<GpuMaterial>,
    /// Lights: emissive triangles first, then the scene's other lights.
    pub lights: Vec<GpuLight>,
    /// Each light's estimated power (luminance of its emitted flux, see [`light_power`]).
    pub light_power: Vec<f64>,
    /// The alias table that picks lights in proportion to `light_power` (padded to a power of
    /// two entries).
    pub light_alias: Vec<GpuAliasEntry>,
    /// The environment map's size and rotation (width 0 when the scene has none).
    pub environment: GpuEnvironment,
    /// The environment map's texels and sampling weights ([`crate::model::environment::Distribution`]);
    /// one zero texel when there is no map.
    pub env_texels: Vec<[f32; 4]>,
    /// The environment map's CDFs; `[0, 1]` when there is no map.
    pub env_cdf: Vec<f32>,
    /// The rough plastics' coating tables ([`plastic::PlasticTables`]); one zero when there
    /// is none.
    pub plastic_tables: Vec<f32>,
    /// Vertex attributes per primitive, in the primitives' order, then the tangents of the
    /// normal-mapped triangles, which their attributes index; empty when no mesh has texture
    /// coordinates, normals or tangents.
    pub attributes: Vec<GpuTriangleAttributes>,
    /// The texture table: one entry per material slot with a texture.
    pub textures: Vec<GpuTextureInfo>,
    /// Every texture's texels (RGBA8), one image after another.
    pub texels: Vec<u32>,
    /// Depth of the BVH (in node levels for [`BvhKind::Cwbvh`]).
    pub bvh_depth: usize,
    /// Time spent building the BVH.
    pub bvh_time: Duration,
    /// Primitives reaching beyond ±[`crate::TRACED_EXTENT`], whose boxes the BVH clips there.
    pub clipped_primitives: usize,
    /// Whether the camera has a thin lens (depth of field).
    pub thin_lens: bool,
    /// The participating media, each material's sides' media and the camera's.
    pub media: super::media::PackedMedia,
}

impl CompiledScene {
    /// Bytes of the geometry the GPU holds: primitives, BVH nodes and vertex attributes.
    pub fn geometry_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.primitives.as_slice())
            + self.bvh.len()
            + std::mem::size_of_val(self.attributes.as_slice())) as u64
    }

    /// Flattens shapes into primitives, collects lights and builds a BVH2.
    pub fn new(scene: &Scene) -> Result<CompiledScene, String> {
        Self::with_bvh(scene, BvhKind::Bvh2)
    }

    /// Flattens shapes into primitives, collects lights and builds a BVH of `kind`. WGSL that
    /// traverses it needs `kind`'s flag ([`BvhKind::flag`]).
    pub fn with_bvh(scene: &Scene, kind: BvhKind) -> Result<CompiledScene, String> {
        let material_index: BTreeMap<&str, u32> = scene
            .materials
            .keys()
            .enumerate()
            .map(|(i, k)| (k.as_str(), i as u32))
            .collect();
        let mut packed = PackedTextures::new(&scene.textures)?;
        let mut tables = plastic::PlasticTables::default();
        let materials = scene
            .materials
            .iter()
            .map(|(name, m)| {
                gpu_material(m, &mut packed, &scene.textures, &mut tables)
                    .map_err(|e| format!("material '{name}': {e}"))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let media = super::media::pack(scene)?;
        let plastic_tables = if tables.data.is_empty() { vec![0.0] } else { tables.data };
        let flatten::Geometry {
            primitives: prims,
            mut lights,
            attributes: attrs,
            tangents,
        } = flatten::flatten_shapes(scene, &material_index)?;
        let sky = flatten::push_scene_lights(&scene.lights, &mut lights)?;
        let (boxes, clipped_primitives) = traced_boxes(&prims);
        let (lo, hi) = boxes
            .iter()
            .fold((Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)), |(lo, hi), (a, b)| {
                (lo.min(*a), hi.max(*b))
            });
        let start = Instant::now();
        let (bvh, order, bvh_depth) = build_bvh(kind, &boxes)?;
        let bvh_time = start.elapsed();
        let primitives: Vec<GpuPrimitive> = order
            .iter()
            .map(|&i| mark_alpha_masked(prims[i as usize], &materials))
            .collect();
        let mut attributes = attrs.map_or_else(Vec::new, |a| order.iter().map(|&i| a[i as usize]).collect());
        flatten::append_tangents(&mut attributes, tangents)?;
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo) * 0.5).length();
        let mean_env_luminance = sky.distribution.as_ref().map_or(0.0, |d| d.mean_luminance);
        let light_power: Vec<f64> = lights
            .iter()
            .map(|l| light_power(l, radius as f64, mean_env_luminance))
            .collect();
        let light_alias = alias::build(&light_power)?;
        let (env_texels, env_cdf) = match sky.distribution {
            Some(d) => (d.texels, d.cdf),
            None => (vec![[0.0; 4]], vec![0.0, 1.0]),
        };
        let info = GpuSceneInfo {
            center: center.into(),
            radius,
            num_lights: lights.len() as u32,
            background: sky.background,
            num_primitives: primitives.len() as u32,
            num_materials: scene.materials.len() as u32,
        };
        Ok(CompiledScene {
            info,
            primitives,
            bvh_kind: kind,
            bvh,
            order,
            materials,
            lights,
            light_power,
            light_alias,
            environment: sky.environment,
            env_texels,
            env_cdf,
            plastic_tables,
            attributes,
            textures: packed.infos,
            texels: packed.texels,
            bvh_depth,
            bvh_time,
            clipped_primitives,
            thin_lens: scene.camera.as_ref().is_some_and(|c| c.lens.is_some()),
            media,
        })
    }
}

/// `p` with `primitive_kind::ALPHA_MASKED` set when it is a triangle of an alpha-masked
/// material, so that traversal tests its alpha without loading the material.
fn mark_alpha_masked(mut p: GpuPrimitive, materials: &[GpuMaterial]) -> GpuPrimitive {
    if p.kind == primitive_kind::TRIANGLE && materials[p.material as usize].flags & material_flags::ALPHA_MASK != 0 {
        p.kind |= primitive_kind::ALPHA_MASKED;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu;
    use crate::parse::scene_file::parse_scene;
    use crate::parse::scene_file::tests::BASE;

    #[test]
    fn a_valid_scene_compiles() {
        let scene = parse_scene("s.ron", BASE).unwrap();
        let c = CompiledScene::new(&scene).unwrap();
        assert_eq!((c.primitives.len(), c.lights.len(), c.info.background), (1, 1, -1));
        assert!(
            (c.info.radius - 3f32.sqrt()).abs() < 1e-6,
            "bounding sphere of the unit sphere's box"
        );
    }

    #[test]
    fn both_bvh_kinds_compile_with_their_own_primitive_order() {
        let text = BASE.replace(
            "shapes: [",
            "shapes: [Sphere(center: (3.0, 0.0, 0.0), radius: 0.5, material: \"m\"), Triangle(vertices: ((0.0, 0.0, 2.0), (1.0, 0.0, 2.0), (0.0, 1.0, 2.0)), material: \"m\"), ",
        );
        let scene = parse_scene("s.ron", &text).unwrap();
        for (kind, node_size) in [
            (BvhKind::Bvh2, size_of::<gpu::GpuBvhNode>()),
            (BvhKind::Cwbvh, size_of::<gpu::GpuCwbvhNode>()),
        ] {
            let c = CompiledScene::with_bvh(&scene, kind).unwrap();
            assert_eq!(c.bvh_kind, kind);
            assert!(!c.bvh.is_empty() && c.bvh.len().is_multiple_of(node_size), "{kind:?}");
            let mut order = c.order.clone();
            order.sort();
            assert_eq!(order, vec![0, 1, 2], "{kind:?}: order is a permutation");
            for (p, &i) in c.primitives.iter().zip(&c.order) {
                let kind_of_shape =
                    [primitive_kind::SPHERE, primitive_kind::TRIANGLE, primitive_kind::SPHERE][i as usize];
                assert_eq!(p.kind, kind_of_shape, "{kind:?}: primitives follow order");
            }
            assert_eq!(c.resources(&CompiledScene::camera(&scene, 1, 1))["bvh"], c.bvh);
        }
    }

    #[test]
    fn triangles_of_alpha_masked_materials_are_marked() {
        let text = BASE
            .replace(
                "materials: {",
                "materials: { \"cut\": (pbr: Some((alpha_cutoff: Some(0.5)))), ",
            )
            .replace(
                "shapes: [",
                "shapes: [Triangle(vertices: ((0.0, 0.0, 2.0), (1.0, 0.0, 2.0), (0.0, 1.0, 2.0)), material: \"cut\"), \
                 Triangle(vertices: ((0.0, 0.0, 3.0), (1.0, 0.0, 3.0), (0.0, 1.0, 3.0)), material: \"m\"), ",
            );
        let scene = parse_scene("s.ron", &text).unwrap();
        for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
            let c = CompiledScene::with_bvh(&scene, kind).unwrap();
            for (p, &i) in c.primitives.iter().zip(&c.order) {
                let expected = [
                    primitive_kind::TRIANGLE | primitive_kind::ALPHA_MASKED,
                    primitive_kind::TRIANGLE,
                    primitive_kind::SPHERE,
                ][i as usize];
                assert_eq!(p.kind, expected, "{kind:?}: shape {i}");
            }
        }
    }

    /// The errors of both BVH kinds for the base scene with `shape` first.
    fn bvh_errors(shape: &str) -> Vec<String> {
        let scene = parse_scene("s.ron", &BASE.replace("shapes: [", &format!("shapes: [{shape}, "))).unwrap();
        [BvhKind::Bvh2, BvhKind::Cwbvh]
            .map(|kind| CompiledScene::with_bvh(&scene, kind).unwrap_err())
            .to_vec()
    }

    #[test]
    fn mesh_index_out_of_range_is_an_error() {
        for e in
            bvh_errors("Mesh(positions: [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)], indices: [(0, 1, 2)], material: \"m\")")
        {
            assert!(
                e.contains("shape 0") && e.contains("vertex 2") && e.contains("2 vertices"),
                "{e}"
            );
        }
    }

    #[test]
    fn huge_or_non_finite_coordinates_are_errors() {
        for (bad, shown) in [
            ("3.4028235e38", "340282350000000000000000000000000000000"),
            ("NaN", "NaN"),
            ("inf", "inf"),
        ] {
            let quad = format!(
                "Quad(corners: ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), ({bad}, 1.0, 0.0), (0.0, 1.0, 0.0)), material: \"m\")"
            );
            for e in bvh_errors(&quad) {
                assert!(e.starts_with("shape 0: coordinate ") && e.contains(shown), "{e}");
            }
        }
    }

    #[test]
    fn quads_split_into_two_triangles_with_the_quads_normal() {
        let text = BASE.replace(
            "shapes: [",
            "shapes: [Quad(corners: ((-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0), (-1.0, 1.0, 0.0)), material: \"m\", emission: (1.0, 2.0, 3.0)), ",
        );
        let c = CompiledScene::new(&parse_scene("s.ron", &text).unwrap()).unwrap();
        let areas: Vec<f32> = c
            .lights
            .iter()
            .filter(|l| l.kind == gpu::light_kind::AREA)
            .map(|l| 1.0 / l.inv_area)
            .collect();
        assert_eq!(areas, vec![2.0, 2.0]);
        assert!(
            c.lights
                .iter()
                .filter(|l| l.kind == gpu::light_kind::AREA)
                .all(|l| l.normal == [0.0, 0.0, 1.0])
        );
    }
}
