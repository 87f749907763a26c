//! lightgraph-scenes: the scene model, RON scene files, validation, BVH building and the
//! GPU data the light-transport shaders read.

pub mod alias;
pub mod bvh;
pub mod cwbvh;
pub mod environment;
pub mod features;
mod flatten;
pub mod gltf;
pub mod gpu;
pub mod mitsuba;
pub mod model;
pub mod placement;
pub mod plastic;
pub mod split;
pub mod tangents;
pub mod texture;

use bvh::BvhKind;
use glam::{Vec3, Vec3A};
use gpu::{
    GpuAliasEntry, GpuCamera, GpuEnvironment, GpuLight, GpuMaterial, GpuPrimitive, GpuSceneInfo, GpuTextureInfo,
    GpuTriangleAttributes, light_kind, material_flags, primitive_kind,
};
use model::{Camera, FovAxis, Light, Look, Scene, Shape};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use texture::PackedTextures;

/// A scene error: the file, a position where one is known, and the problem.
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {message}", at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file.
    pub file: String,
    /// 1-based line and column.
    pub at: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

fn locate(text: &str, needle: &str) -> Option<(usize, usize)> {
    let offset = text.find(needle)?;
    let before = &text[..offset];
    Some((
        before.matches('\n').count() + 1,
        before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1,
    ))
}

/// Parses and validates the RON scene `text` of `file`.
pub fn parse_scene(file: &str, text: &str) -> Result<Scene, SceneError> {
    let scene: Scene = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| SceneError {
            file: file.to_string(),
            at: Some((e.span.start.line, e.span.start.col)),
            message: e.code.to_string(),
        })?;
    let err = |needle: &str, message: String| SceneError {
        file: file.to_string(),
        at: locate(text, needle),
        message,
    };
    // A glTF asset or a Mitsuba file brings shapes, lights and maybe a camera.
    let imports = scene.gltf.is_some() || scene.mitsuba.is_some();
    if scene.gltf.is_some() && scene.mitsuba.is_some() {
        return Err(err(
            "mitsuba",
            "the scene has both a glTF asset and a Mitsuba file; keep one".into(),
        ));
    }
    if scene.shapes.is_empty() && !imports {
        return Err(err("shapes", "the scene is empty: it has no shapes".into()));
    }
    for shape in &scene.shapes {
        let material = shape.material();
        if !scene.materials.contains_key(material) {
            let known: Vec<&str> = scene.materials.keys().map(|s| s.as_str()).collect();
            return Err(err(
                &format!("\"{material}\""),
                format!("unknown material '{material}' (materials: {})", known.join(", ")),
            ));
        }
        if let Shape::Sphere { radius, .. } = shape
            && (*radius <= 0.0 || !radius.is_finite())
        {
            return Err(err("Sphere", format!("sphere radius {radius} is not positive")));
        }
    }
    let emissive = scene.shapes.iter().any(Shape::emits);
    if !emissive && scene.lights.is_empty() && !imports {
        return Err(err(
            "lights",
            "the scene has no light: add an emissive shape or a light (Point, Directional, Background)".into(),
        ));
    }
    check_lights(&scene.lights).map_err(|(needle, message)| err(needle, message))?;
    if !scene.gltf_instances.is_empty() && scene.gltf.is_none() {
        return Err(err(
            "gltf_instances",
            "gltf_instances places copies of a glTF asset, but the scene has none (gltf: \"...\")".into(),
        ));
    }
    placement::check(&scene.gltf_instances).map_err(|(needle, message)| err(needle, message))?;
    let (w, h) = scene.resolution;
    if w == 0 || h == 0 {
        return Err(err("resolution", "resolution must be at least 1x1".into()));
    }
    match (&scene.camera, &scene.gltf_camera, &scene.gltf) {
        (Some(camera), None, _) => check_fov(camera.fov_degrees).map_err(|e| err("fov_degrees", e))?,
        (None, Some(_), Some(_)) => {}
        (Some(_), Some(_), _) => {
            return Err(err(
                "gltf_camera",
                "the scene has both a camera and a gltf_camera; keep one".into(),
            ));
        }
        (None, Some(_), None) => {
            return Err(err(
                "gltf_camera",
                "gltf_camera needs a glTF asset (gltf: \"...\")".into(),
            ));
        }
        (None, None, _) if scene.mitsuba.is_some() => {}
        (None, None, _) => {
            return Err(err(
                "Scene",
                "the scene has no camera: add camera: (position: .., look: .., up: .., fov_degrees: ..), or gltf_camera: Index(0) or Name(\"...\") with a glTF asset".into(),
            ));
        }
    }
    if scene.integrator.max_path_length == 0 {
        return Err(err("max_path_length", "max_path_length must be at least 1".into()));
    }
    Ok(scene)
}

fn check_fov(fov_degrees: f32) -> Result<(), String> {
    if fov_degrees > 0.0 && fov_degrees < 180.0 {
        Ok(())
    } else {
        Err(format!("field of view {fov_degrees} is not in (0, 180) degrees"))
    }
}

/// Imports the scene's glTF asset (a path below `asset_root`) into its shapes, materials,
/// textures, camera (`gltf_camera`) and lights (KHR_lights_punctual), or its Mitsuba file
/// (`mitsuba`, [`add_mitsuba`]), loads the environment maps its lights name (paths below
/// `asset_root` too), then checks that the scene has geometry and light.
/// Approximations of the import are printed to stderr as warnings.
pub fn resolve_gltf(scene: &mut Scene, file: &str, asset_root: Option<&std::path::Path>) -> Result<(), SceneError> {
    let err = |message: String| SceneError {
        file: file.to_string(),
        at: None,
        message,
    };
    if let Some(asset) = scene.gltf.clone() {
        let path = asset_file(asset_root, &asset, "the glTF asset").map_err(err)?;
        add_gltf(scene, &path).map_err(err)?;
        if scene.gltf_diffuse {
            make_diffuse(scene);
        }
    }
    if let Some(asset) = scene.mitsuba.clone() {
        let path = asset_file(asset_root, &asset, "the Mitsuba scene").map_err(err)?;
        add_mitsuba(scene, &path)?;
    }
    for light in &mut scene.lights {
        if let Light::Environment { file: image, map, .. } = light
            && map.is_none()
        {
            let path = asset_file(asset_root, image, "the environment map").map_err(err)?;
            *map = Some(std::sync::Arc::new(
                environment::EnvironmentMap::load(&path).map_err(err)?,
            ));
        }
    }
    check_lights(&scene.lights).map_err(|(_, message)| err(message))?;
    check_resolved(scene).map_err(err)
}

/// The file `asset` (`what` names it in errors) below the asset root, which must hold it.
fn asset_file(asset_root: Option<&std::path::Path>, asset: &str, what: &str) -> Result<std::path::PathBuf, String> {
    let root = asset_root.ok_or_else(|| {
        format!(
            "the scene needs {what} '{asset}' but there is no asset root: {}",
            fetch_help(asset, None)
        )
    })?;
    let path = root.join(asset);
    if !path.is_file() {
        return Err(format!(
            "{what} '{asset}' not found under the asset root {}: {}",
            root.display(),
            fetch_help(asset, Some(root))
        ));
    }
    Ok(path)
}

/// Imports the Mitsuba scene file at `path` into `scene`: its shapes, materials, textures
/// and emitters join the scene's, and its sensor is the camera unless the scene has one.
/// Its approximations are printed to stderr as warnings.
fn add_mitsuba(scene: &mut Scene, path: &std::path::Path) -> Result<(), SceneError> {
    let imported = mitsuba::load(path)?;
    for warning in &imported.warnings {
        eprintln!("warning: {warning}");
    }
    let mut imported = imported.scene;
    if let Some(name) = imported.materials.keys().find(|n| scene.materials.contains_key(*n)) {
        return Err(SceneError {
            file: path.display().to_string(),
            at: None,
            message: format!("its material '{name}' has the name of one of the scene's: rename the scene's"),
        });
    }
    offset_textures(&mut imported.materials, scene.textures.len() as u32);
    scene.textures.append(&mut imported.textures);
    scene.materials.append(&mut imported.materials);
    scene.shapes.append(&mut imported.shapes);
    scene.lights.append(&mut imported.lights);
    if scene.camera.is_none() {
        scene.camera = imported.camera;
    }
    Ok(())
}

/// Moves the texture indices of `materials` on by `first` (their textures are appended to a
/// scene that has `first` already).
fn offset_textures(materials: &mut BTreeMap<String, model::Material>, first: u32) {
    for pbr in materials.values_mut().filter_map(|m| m.pbr.as_mut()) {
        let t = &mut pbr.textures;
        let normal = t.normal.as_mut().map(|n| &mut n.texture);
        for r in [
            t.base_color.as_mut(),
            t.metallic_roughness.as_mut(),
            t.emissive.as_mut(),
            normal,
        ]
        .into_iter()
        .flatten()
        {
            r.texture += first;
        }
    }
}

/// What to do about an asset file missing under the asset root `root` (None: no root): where
/// the root is looked for, and the command that gets the asset (its first folder is the asset's
/// name in `lightgraph assets`).
fn fetch_help(asset: &str, root: Option<&std::path::Path>) -> String {
    let to = root.map_or("DIR".to_string(), |r| r.display().to_string());
    let name = asset.split(['/', '\\']).next().filter(|n| *n != asset);
    let get = match name {
        Some(name) => format!("`lightgraph assets fetch {name} --to {to}` downloads it where it has a public source"),
        None => "put it below the asset root".to_string(),
    };
    format!(
        "{get}, and `lightgraph assets list` says where each asset comes from (the asset root is --assets DIR, else LIGHTGRAPH_ASSETS, else ../shared/scenes beside the repository)"
    )
}

/// Makes every glTF material of `scene` (named `gltf:...`) a pure Lambertian: no specular
/// layer (index of refraction 1), no metal, no transmission; base colour and alpha stay.
fn make_diffuse(scene: &mut Scene) {
    let gltf = scene.materials.iter_mut().filter(|(name, _)| name.starts_with("gltf:"));
    for p in gltf.filter_map(|(_, m)| m.pbr.as_mut()) {
        p.ior = 1.0;
        p.metallic = 0.0;
        p.transmission = 0.0;
        p.textures.metallic_roughness = None;
    }
}

/// Checks that a scene with its glTF asset imported has geometry and light.
fn check_resolved(scene: &Scene) -> Result<(), String> {
    if scene.shapes.is_empty() {
        return Err("the scene is empty: it has no shapes".into());
    }
    let emissive = scene.shapes.iter().any(Shape::emits);
    if !emissive && scene.lights.is_empty() {
        return Err("the scene has no light: add an emissive shape or a light (Point, Directional, Background)".into());
    }
    Ok(())
}

/// Imports the glTF file at `path` into `scene` and picks its `gltf_camera`; returns the
/// asset's cameras.
fn add_gltf(scene: &mut Scene, path: &std::path::Path) -> Result<Vec<gltf::ImportedCamera>, String> {
    let mut imported = gltf::import(path)?;
    for warning in &imported.warnings {
        eprintln!("warning: {}: {warning}", path.display());
    }
    // The asset's texture indices count from the scene's textures so far.
    offset_textures(&mut imported.materials, scene.textures.len() as u32);
    scene.textures.extend(imported.textures);
    if let Some(wanted) = &scene.gltf_camera {
        let found = imported.cameras.iter().find(|c| match wanted {
            model::GltfCamera::Index(i) => c.index == *i,
            model::GltfCamera::Name(n) => c.names.contains(n),
        });
        let Some(found) = found else {
            let known: Vec<String> = imported
                .cameras
                .iter()
                .map(|c| format!("{} {:?}", c.index, c.names))
                .collect();
            return Err(format!(
                "{}: no perspective camera {wanted:?} placed by a node (cameras: {})",
                path.display(),
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            ));
        };
        check_fov(found.camera.fov_degrees).map_err(|e| format!("{}: camera {}: {e}", path.display(), found.index))?;
        scene.camera = Some(found.camera.clone());
    }
    scene.materials.extend(imported.materials);
    scene
        .shapes
        .extend(placement::place(imported.shapes, &scene.gltf_instances));
    scene.lights.extend(imported.lights);
    Ok(imported.cameras)
}

/// The scene of a bare glTF file (`.gltf` or `.glb`): its first perspective camera (at the
/// camera's aspect ratio, 512 texels high), else a default camera framing its bounds, and a
/// constant white background when it has no light. Also returns a note for each of these
/// defaults taken.
pub fn scene_from_gltf(path: &std::path::Path) -> Result<(Scene, Vec<String>), SceneError> {
    let file = path.display().to_string();
    let err = |message: String| SceneError {
        file: file.clone(),
        at: None,
        message,
    };
    let mut scene = Scene {
        description: format!("the glTF asset {file}"),
        camera: None,
        gltf_camera: None,
        resolution: (512, 512),
        materials: BTreeMap::new(),
        shapes: Vec::new(),
        lights: Vec::new(),
        integrator: Default::default(),
        gltf: Some(file.clone()),
        gltf_diffuse: false,
        gltf_instances: Vec::new(),
        mitsuba: None,
        textures: Vec::new(),
    };
    let cameras = add_gltf(&mut scene, path).map_err(err)?;
    let mut notes = Vec::new();
    match cameras.iter().find(|c| check_fov(c.camera.fov_degrees).is_ok()) {
        Some(c) => {
            scene.camera = Some(c.camera.clone());
            if let Some(aspect) = c.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0) {
                scene.resolution = (((512.0 * aspect).round() as u32).clamp(1, 16384), 512);
            }
        }
        None => {
            scene.camera = Some(default_camera(&scene));
            notes.push("it has no perspective camera: a default camera frames its bounds".to_string());
        }
    }
    if !scene.shapes.iter().any(Shape::emits) && scene.lights.is_empty() {
        scene.lights.push(Light::Background {
            radiance: [1.0; 3],
            scale: 1.0,
        });
        notes.push("it has no light: a constant white background (radiance 1) lights it".to_string());
    }
    check_resolved(&scene).map_err(err)?;
    Ok((scene, notes))
}

/// A camera looking down -Z (glTF's default view) at the centre of the scene's bounding
/// sphere, far enough back for a vertical field of view of 45 degrees to hold all of it.
pub fn default_camera(scene: &Scene) -> Camera {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let mut add = |p: Vec3, r: f32| {
        if p.is_finite() && r.is_finite() {
            lo = lo.min(p - r);
            hi = hi.max(p + r);
        }
    };
    for shape in &scene.shapes {
        match shape {
            Shape::Triangle { vertices, .. } => vertices.iter().for_each(|&v| add(v3(v), 0.0)),
            Shape::Quad { corners, .. } => corners.iter().for_each(|&v| add(v3(v), 0.0)),
            Shape::Mesh { positions, .. } => positions.iter().for_each(|&v| add(v3(v), 0.0)),
            Shape::Sphere { center, radius, .. } => add(v3(*center), *radius),
        }
    }
    let (center, radius) = if lo.x <= hi.x {
        ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-6))
    } else {
        (Vec3::ZERO, 1.0)
    };
    let fov_degrees: f32 = 45.0;
    let distance = radius / (fov_degrees.to_radians() * 0.5).sin();
    Camera {
        position: (center + Vec3::Z * distance).to_array(),
        look: Look::Target(center.to_array()),
        up: [0.0, 1.0, 0.0],
        fov_degrees,
        fov_axis: FovAxis::Smaller,
        lens: None,
    }
}

/// The scene flattened for the GPU, with its BVH.
#[derive(Debug, Clone)]
pub struct CompiledScene {
    /// Scene-wide values.
    pub info: GpuSceneInfo,
    /// Primitives in the leaf order of the BVH.
    pub primitives: Vec<GpuPrimitive>,
    /// The kind of BVH built.
    pub bvh_kind: BvhKind,
    /// The BVH's nodes as the GPU reads them: [`gpu::GpuBvhNode`]s for [`BvhKind::Bvh2`],
    /// [`gpu::GpuCwbvhNode`]s for [`BvhKind::Cwbvh`].
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
    /// The environment map's texels and sampling weights ([`environment::Distribution`]);
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
    /// Primitives reaching beyond ±[`TRACED_EXTENT`], whose boxes the BVH clips there.
    pub clipped_primitives: usize,
    /// Whether the camera has a thin lens (depth of field).
    pub thin_lens: bool,
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
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
        })
    }

    /// The camera for an image of `width` x `height` pixels.
    pub fn camera(scene: &Scene, width: u32, height: u32) -> GpuCamera {
        let c = &scene.camera.clone().unwrap_or_else(|| default_camera(scene));
        let position = v3(c.position);
        let forward = match c.look {
            Look::Forward(d) => v3(d),
            Look::Target(t) => v3(t) - position,
        }
        .normalize();
        let right = forward.cross(v3(c.up)).normalize();
        let up = right.cross(forward);
        let t = (c.fov_degrees.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let horizontal = match c.fov_axis {
            FovAxis::Horizontal => true,
            FovAxis::Vertical => false,
            FovAxis::Smaller => width <= height,
        };
        let (tx, ty) = if horizontal { (t, t / aspect) } else { (t * aspect, t) };
        GpuCamera {
            position: position.into(),
            width: width as f32,
            forward: forward.into(),
            height: height as f32,
            right: (right * tx).into(),
            lens_radius: c.lens.map_or(0.0, |l| l.aperture_radius),
            up: (up * ty).into(),
            focus_distance: c.lens.map_or(0.0, |l| l.focus_distance),
        }
    }

    /// The external resources of the light-transport graphs, by resource name.
    pub fn resources(&self, camera: &GpuCamera) -> BTreeMap<String, Vec<u8>> {
        let mut out = BTreeMap::new();
        out.insert("scene".to_string(), bytemuck::bytes_of(&self.info).to_vec());
        out.insert("camera".to_string(), bytemuck::bytes_of(camera).to_vec());
        out.insert(
            "primitives".to_string(),
            bytemuck::cast_slice(&self.primitives).to_vec(),
        );
        out.insert("bvh".to_string(), self.bvh.clone());
        out.insert("materials".to_string(), bytemuck::cast_slice(&self.materials).to_vec());
        out.insert("lights".to_string(), bytemuck::cast_slice(&self.lights).to_vec());
        out.insert(
            "light_alias".to_string(),
            bytemuck::cast_slice(&self.light_alias).to_vec(),
        );
        out.insert(
            "environment".to_string(),
            bytemuck::bytes_of(&self.environment).to_vec(),
        );
        out.insert(
            "env_texels".to_string(),
            bytemuck::cast_slice(&self.env_texels).to_vec(),
        );
        out.insert("env_cdf".to_string(), bytemuck::cast_slice(&self.env_cdf).to_vec());
        out.insert(
            "plastic_tables".to_string(),
            bytemuck::cast_slice(&self.plastic_tables).to_vec(),
        );
        out.insert(
            "attributes".to_string(),
            bytemuck::cast_slice(&self.attributes).to_vec(),
        );
        out.insert("textures".to_string(), bytemuck::cast_slice(&self.textures).to_vec());
        out.insert("texels".to_string(), bytemuck::cast_slice(&self.texels).to_vec());
        out
    }
}

/// A light's estimated power: the luminance of the flux it emits. Area: π A L (one side);
/// point: 4π I; spot: I × its cone's integral of the falloff, 2π ((1 − cos inner) +
/// (cos inner − cos outer) / 3) for glTF's, 2π (1 − (sin θo − sin θi) / (θo − θi)) for
/// Mitsuba's linear one; directional: E π r² through a disk of the scene's bounding
/// radius `radius`; background and environment: the flux π L̄ × π r² they send onto one side of
/// that disk, with L̄ the mean luminance over the sphere (`mean_env_luminance` × scale for a
/// map). Only ratios matter: they set how often each light is picked.
pub fn light_power(l: &GpuLight, radius: f64, mean_env_luminance: f64) -> f64 {
    use std::f64::consts::PI;
    let lum = alias::luminance(l.radiance);
    let disk = PI * radius * radius;
    match l.kind {
        light_kind::AREA if l.inv_area > 0.0 => PI * lum / l.inv_area as f64,
        light_kind::AREA => 0.0,
        light_kind::POINT => 4.0 * PI * lum,
        light_kind::SPOT if l.e2[0] != 0.0 => {
            // Linear in the angle: 1 - (sin θo - sin θi) / (θo - θi) over the solid angle 2π.
            let (ti, to) = ((l.cos_inner as f64).acos(), (l.cos_outer as f64).acos());
            let ramp = if to > ti {
                (to.sin() - ti.sin()) / (to - ti)
            } else {
                ti.cos()
            };
            2.0 * PI * lum * (1.0 - ramp)
        }
        light_kind::SPOT => {
            let (ci, co) = (l.cos_inner as f64, l.cos_outer as f64);
            2.0 * PI * lum * ((1.0 - ci) + (ci - co).max(0.0) / 3.0)
        }
        light_kind::DIRECTIONAL => lum * disk,
        light_kind::BACKGROUND => PI * lum * disk,
        _ => PI * lum * mean_env_luminance * disk,
    }
}

/// Checks the lights of a scene: at most one Background or Environment, spot cones within
/// 0 ≤ inner ≤ outer ≤ 90 degrees. Errors give a word to locate and the message.
fn check_lights(lights: &[Light]) -> Result<(), (&'static str, String)> {
    let environments = lights
        .iter()
        .filter(|l| matches!(l, Light::Background { .. } | Light::Environment { .. }))
        .count();
    if environments > 1 {
        return Err((
            "Environment",
            format!("a scene has at most one Background or Environment light; this one has {environments}"),
        ));
    }
    for light in lights {
        if let Light::Spot {
            inner_cone_degrees: inner,
            outer_cone_degrees: outer,
            ..
        } = light
            && !(0.0 <= *inner && inner <= outer && *outer <= 90.0)
        {
            return Err((
                "Spot",
                format!(
                    "spot light cone angles inner {inner} and outer {outer} degrees must satisfy 0 <= inner <= outer <= 90"
                ),
            ));
        }
    }
    Ok(())
}

/// A material as the GPU reads it, its textures added to `packed` and a rough plastic's
/// coating table to `tables`.
fn gpu_material(
    m: &model::Material,
    packed: &mut PackedTextures,
    textures: &[texture::Texture],
    tables: &mut plastic::PlasticTables,
) -> Result<GpuMaterial, String> {
    let two_sided = if m.two_sided { gpu::material_flags::TWO_SIDED } else { 0 };
    Ok(match &m.pbr {
        None => GpuMaterial {
            diffuse: m.diffuse,
            phong_exponent: m.phong_exponent,
            phong: m.phong,
            ior: m.ior,
            mirror: m.mirror,
            flags: two_sided,
            ..GpuMaterial::default()
        },
        Some(p) => {
            let mut slot = |r: &Option<texture::TextureRef>, srgb: bool| match r {
                None => Ok(-1),
                Some(r) if (r.texture as usize) < textures.len() => Ok(packed.add(r, srgb, textures)),
                Some(r) => Err(format!("texture {} of {}", r.texture, textures.len())),
            };
            let mask = if p.alpha_cutoff.is_some() {
                gpu::material_flags::ALPHA_MASK
            } else {
                0
            };
            let thin = if p.thin_walled && p.transmission > 0.0 {
                gpu::material_flags::THIN_WALLED
            } else {
                0
            };
            let (eta, k) = p.conductor.map_or(([0.0; 3], [0.0; 3]), |c| (c.eta, c.k));
            let table = rough_plastic_table(p, tables)?;
            let rough_plastic = if table.is_some() {
                gpu::material_flags::ROUGH_PLASTIC
            } else {
                0
            };
            GpuMaterial {
                diffuse: p.base_color,
                phong_exponent: table.unwrap_or(0) as f32,
                ior: p.ior,
                mirror: eta,
                phong: k,
                flags: two_sided | gpu::material_flags::PBR | mask | thin | rough_plastic | pbr_model_flags(p),
                emission: p.emission,
                metallic: p.metallic,
                roughness: p.roughness,
                transmission: p.transmission,
                alpha: p.alpha,
                alpha_cutoff: p.alpha_cutoff.unwrap_or(0.0),
                base_color_texture: slot(&p.textures.base_color, true)?,
                metallic_roughness_texture: slot(&p.textures.metallic_roughness, false)?,
                emissive_texture: slot(&p.textures.emissive, true)?,
                normal_texture: slot(&p.textures.normal.map(|n| n.texture), false)?,
            }
        }
    })
}

/// The offset in `tables` of a rough plastic's coating table (added on first use); `None` for
/// other materials, smooth plastics among them.
fn rough_plastic_table(p: &model::Pbr, tables: &mut plastic::PlasticTables) -> Result<Option<u32>, String> {
    if p.plastic.is_none() || p.roughness <= 0.0 {
        return Ok(None);
    }
    let offset = tables.offset(p.roughness.min(1.0), p.ior, p.distribution)?;
    // The GPU reads the offset from an f32, exact below 2^24.
    if offset >= 1 << 24 {
        return Err("too many rough plastic coatings: their tables exceed 2^24 floats".to_string());
    }
    Ok(Some(offset))
}

/// The flags of a PBR material's microfacet distribution and plastic model.
fn pbr_model_flags(p: &model::Pbr) -> u32 {
    let beckmann = match p.distribution {
        model::Microfacet::Ggx => 0,
        model::Microfacet::Beckmann => gpu::material_flags::BECKMANN,
    };
    let plastic = match p.plastic {
        None => 0,
        Some(model::Plastic { nonlinear: false }) => gpu::material_flags::PLASTIC,
        Some(model::Plastic { nonlinear: true }) => {
            gpu::material_flags::PLASTIC | gpu::material_flags::PLASTIC_NONLINEAR
        }
    };
    let conductor = if p.conductor.is_some() {
        gpu::material_flags::CONDUCTOR
    } else {
        0
    };
    let separable = match p.masking {
        model::Masking::HeightCorrelated => 0,
        model::Masking::Separable => gpu::material_flags::SMITH_SEPARABLE,
    };
    beckmann | plastic | conductor | separable
}

/// The largest coordinate (or sphere radius) a shape may have: as far as a ray travels
/// (`INFINITE_DISTANCE` in the WGSL).
pub const MAX_COORDINATE: f32 = 1e30;

/// How far from the origin the BVH bounds geometry. Beyond it, primitive boxes are clipped
/// (rays do not find the parts of primitives out there): the builders' surface areas stay
/// finite in f32, and f32 positions that far apart are coarser than 1e8 units anyway.
pub const TRACED_EXTENT: f32 = 1e15;

/// The primitives' boxes as the BVH bounds them (clipped to ±[`TRACED_EXTENT`]), and how many
/// were clipped.
fn traced_boxes(prims: &[GpuPrimitive]) -> (Vec<(Vec3A, Vec3A)>, usize) {
    let limit = Vec3A::splat(TRACED_EXTENT);
    let mut clipped = 0;
    let boxes = prims
        .iter()
        .map(|p| {
            let (a, b) = primitive_bounds(p);
            if a.min_element() < -TRACED_EXTENT || b.max_element() > TRACED_EXTENT {
                clipped += 1;
            }
            (a.clamp(-limit, limit), b.clamp(-limit, limit))
        })
        .collect();
    (boxes, clipped)
}

/// A BVH of `kind` over `boxes`: its nodes' bytes, the leaf order of the boxes and its depth.
fn build_bvh(kind: BvhKind, boxes: &[(Vec3A, Vec3A)]) -> Result<(Vec<u8>, Vec<u32>, usize), String> {
    Ok(match kind {
        BvhKind::Bvh2 => {
            let b = bvh::build(boxes)?;
            (bytemuck::cast_slice(&b.nodes).to_vec(), b.order, b.depth)
        }
        BvhKind::Cwbvh => {
            let b = cwbvh::build(boxes)?;
            (bytemuck::cast_slice(&b.nodes).to_vec(), b.order, b.depth)
        }
    })
}

/// `p` with `primitive_kind::ALPHA_MASKED` set when it is a triangle of an alpha-masked
/// material, so that traversal tests its alpha without loading the material.
fn mark_alpha_masked(mut p: GpuPrimitive, materials: &[GpuMaterial]) -> GpuPrimitive {
    if p.kind == primitive_kind::TRIANGLE && materials[p.material as usize].flags & material_flags::ALPHA_MASK != 0 {
        p.kind |= primitive_kind::ALPHA_MASKED;
    }
    p
}

/// The axis-aligned bounds of a primitive.
pub fn primitive_bounds(p: &GpuPrimitive) -> (Vec3A, Vec3A) {
    let a = Vec3A::from_array(p.a);
    if p.kind == primitive_kind::SPHERE {
        let r = Vec3A::splat(p.b[0]);
        (a - r, a + r)
    } else {
        let (b, c) = (a + Vec3A::from_array(p.b), a + Vec3A::from_array(p.c));
        (a.min(b).min(c), a.max(b).max(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    materials: { "m": (diffuse: (0.5, 0.5, 0.5)) },
    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: "m")],
    lights: [Point(position: (0.0, -2.0, 2.0), intensity: (1.0, 1.0, 1.0))],
)"#;

    fn error(text: &str) -> String {
        parse_scene("s.ron", text)
            .expect_err("the scene is refused")
            .to_string()
    }

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

    #[test]
    fn invalid_scenes_are_refused_with_a_location() {
        let e = error(&BASE.replace("material: \"m\")", "material: \"n\")"));
        assert!(e.starts_with("s.ron:4:") && e.contains("unknown material 'n'"), "{e}");
        let e = error(&BASE.replace(
            "lights: [Point(position: (0.0, -2.0, 2.0), intensity: (1.0, 1.0, 1.0))],",
            "",
        ));
        assert!(e.contains("no light"), "{e}");
        let e = error(&BASE.replace(
            "shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: \"m\")]",
            "shapes: []",
        ));
        assert!(e.contains("empty"), "{e}");
        let e = error(&BASE.replace("radius: 1.0", "radius: -1.0"));
        assert!(e.contains("radius"), "{e}");
        let e = error(&BASE.replace("fov_degrees: 40.0", "fov_degrees: 40.0,,"));
        assert!(e.starts_with("s.ron:2:"), "{e}");
        // Spheres do not emit: a field a shape does not have is refused, not ignored.
        let e = error(&BASE.replace("material: \"m\")", "material: \"m\", emission: (1.0, 1.0, 1.0))"));
        assert!(e.starts_with("s.ron:4:") && e.contains("emission"), "{e}");
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
