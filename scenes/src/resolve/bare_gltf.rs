//! The scene of a bare glTF file, with the defaults it lacks.

use super::merge::add_gltf;
use crate::error::SceneError;
use crate::model::checks::{check_fov, check_resolved};
use crate::model::framing::default_camera;
use crate::model::{Light, Scene, Shape};
use std::collections::BTreeMap;

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
        media: BTreeMap::new(),
        camera_medium: None,
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
