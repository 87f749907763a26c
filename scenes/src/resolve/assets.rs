//! A scene's asset files found below the asset root and imported: its glTF asset or Mitsuba
//! file and the environment maps its lights name.

use super::merge::{add_gltf, add_mitsuba};
use crate::error::SceneError;
use crate::model::checks::{check_lights, check_resolved};
use crate::model::{Light, Scene, environment};

/// Imports the scene's glTF asset (a path below `asset_root`) into its shapes, materials,
/// textures, camera (`gltf_camera`) and lights (KHR_lights_punctual), or its Mitsuba file
/// (`mitsuba`, [`crate::parse::mitsuba`]), loads the environment maps its lights name (paths below
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
/// layer (index of refraction 1), no metal, no transmission and so no medium inside; base
/// colour and alpha stay.
fn make_diffuse(scene: &mut Scene) {
    let gltf = scene.materials.iter_mut().filter(|(name, _)| name.starts_with("gltf:"));
    for (_, m) in gltf {
        m.interior = None;
        let Some(p) = m.pbr.as_mut() else { continue };
        p.ior = 1.0;
        p.metallic = 0.0;
        p.transmission = 0.0;
        p.textures.metallic_roughness = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Material, Pbr};

    #[test]
    fn a_mitsuba_files_media_and_sensor_medium_join_the_scene() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data");
        let text = |media: &str| format!("Scene(mitsuba: \"mitsuba/media.xml\", media: {{ {media} }})");
        let mut scene = crate::parse::scene_file::parse_scene("s.ron", &text("")).unwrap();
        resolve_gltf(&mut scene, "s.ron", Some(&root)).unwrap();
        assert_eq!(scene.camera_medium.as_deref(), Some("fog"), "with the file's sensor");
        let media: Vec<&str> = scene.media.keys().map(String::as_str).collect();
        assert_eq!(media, ["fog", "juice", "mitsuba:48:3"]);
        let mut scene = crate::parse::scene_file::parse_scene("s.ron", &text("\"fog\": ()")).unwrap();
        let e = resolve_gltf(&mut scene, "s.ron", Some(&root)).unwrap_err();
        assert!(
            e.message
                .contains("its medium 'fog' has the name of one of the scene's"),
            "{e}"
        );
    }

    #[test]
    fn diffuse_gltf_materials_lose_their_transmission_and_the_medium_inside() {
        let mut scene = crate::parse::scene_file::parse_scene("s.ron", crate::parse::scene_file::tests::BASE).unwrap();
        let glass = Material {
            pbr: Some(Pbr {
                transmission: 1.0,
                ..Default::default()
            }),
            interior: Some("gltf:glass".into()),
            ..Default::default()
        };
        scene.materials.insert("gltf:glass".into(), glass.clone());
        scene.materials.insert("mine".into(), glass);
        make_diffuse(&mut scene);
        let m = &scene.materials["gltf:glass"];
        assert_eq!(
            (m.pbr.as_ref().unwrap().transmission, m.interior.as_deref()),
            (0.0, None)
        );
        assert_eq!(
            scene.materials["mine"].interior.as_deref(),
            Some("gltf:glass"),
            "the scene's own stay"
        );
    }
}
