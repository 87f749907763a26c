//! Imported scenes merged into a scene: their textures, materials, media, shapes (glTF's
//! placed by `gltf_instances`), lights and camera.

use super::placement;
use crate::error::SceneError;
use crate::model::checks::check_fov;
use crate::model::{self, Scene};
use crate::parse::{gltf, mitsuba};
use std::collections::BTreeMap;

/// Imports the Mitsuba scene file at `path` into `scene`: its shapes, materials, media,
/// textures and emitters join the scene's, and its sensor (with the medium it is in) is the
/// camera unless the scene has one. Its approximations are printed to stderr as warnings.
pub(crate) fn add_mitsuba(scene: &mut Scene, path: &std::path::Path) -> Result<(), SceneError> {
    let imported = mitsuba::load(path)?;
    for warning in &imported.warnings {
        eprintln!("warning: {warning}");
    }
    let mut imported = imported.scene;
    let clash = |what: &str, name: &String| SceneError {
        file: path.display().to_string(),
        at: None,
        message: format!("its {what} '{name}' has the name of one of the scene's: rename the scene's"),
    };
    if let Some(name) = imported.materials.keys().find(|n| scene.materials.contains_key(*n)) {
        return Err(clash("material", name));
    }
    if let Some(name) = imported.media.keys().find(|n| scene.media.contains_key(*n)) {
        return Err(clash("medium", name));
    }
    offset_textures(&mut imported.materials, scene.textures.len() as u32);
    scene.textures.append(&mut imported.textures);
    scene.materials.append(&mut imported.materials);
    scene.media.append(&mut imported.media);
    scene.shapes.append(&mut imported.shapes);
    scene.lights.append(&mut imported.lights);
    if scene.camera.is_none() {
        scene.camera = imported.camera;
        scene.camera_medium = imported.camera_medium;
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

/// Imports the glTF file at `path` into `scene` and picks its `gltf_camera`; returns the
/// asset's cameras.
pub(crate) fn add_gltf(scene: &mut Scene, path: &std::path::Path) -> Result<Vec<gltf::ImportedCamera>, String> {
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
    if let Some(name) = imported.media.keys().find(|n| scene.media.contains_key(*n)) {
        return Err(format!(
            "{}: its medium '{name}' has the name of one of the scene's: rename the scene's",
            path.display()
        ));
    }
    scene.materials.extend(imported.materials);
    scene.media.extend(imported.media);
    scene
        .shapes
        .extend(placement::place(imported.shapes, &scene.gltf_instances));
    scene.lights.extend(imported.lights);
    Ok(imported.cameras)
}
