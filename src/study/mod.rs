//! Studies: the best layout of each estimator on a list of scenes, each given the same
//! wall-clock budget against a reference per scene (`lightgraph study`). Per scene the runs
//! are a comparison ([`crate::compare`]); this module chooses the layouts by measurement
//! ([`layouts`]), names the scenes' folders, calls the winner or the tie of each scene
//! ([`verdict`]) and sums the comparisons up ([`summary`]).

pub mod html;
pub mod layouts;
pub mod render;
pub mod summary;
pub mod verdict;

use anyhow::{Result, bail};
use std::path::{Component, Path};

/// The estimators a study runs when none are named: each graph's best layout, chosen by
/// measurement.
pub const DEFAULT_ESTIMATORS: &str = "pt,bpt-lvc,ppm,sppm,pbpm,vcm,pssmlt,mmlt,mvcm,appm";

/// The extensions of scene files (`--scene` takes RON, glTF and Mitsuba files).
const SCENE_FILE_EXTENSIONS: [&str; 4] = ["ron", "gltf", "glb", "xml"];

/// The folder names of `scenes`' outputs and references, one each, file-name safe: a
/// built-in name as it is, a scene file's stem, with as many of its parent folders in front
/// as it takes to tell it from the others (Bitterli's scenes are all `scene.xml`:
/// `veach-bidir/scene.xml` gives `veach-bidir-scene`). An error for a scene named twice.
pub fn scene_folders(scenes: &[String]) -> Result<Vec<String>> {
    let parts: Vec<Vec<String>> = scenes.iter().map(|s| name_parts(s)).collect();
    let mut depth = vec![1; scenes.len()];
    loop {
        let folders: Vec<String> = parts
            .iter()
            .zip(&depth)
            .map(|(p, &d)| {
                let mut taken: Vec<&str> = p.iter().take(d).map(String::as_str).collect();
                taken.reverse();
                crate::compare::file_stem(&taken.join("-"))
            })
            .collect();
        let clashing: Vec<usize> = (0..folders.len())
            .filter(|&i| folders.iter().filter(|f| **f == folders[i]).count() > 1)
            .collect();
        let Some(&first) = clashing.first() else {
            return Ok(folders);
        };
        let mut grew = false;
        for &i in &clashing {
            if depth[i] < parts[i].len() {
                depth[i] += 1;
                grew = true;
            }
        }
        if !grew {
            bail!(
                "scene '{}' is named twice (as the output folder '{}' shows)",
                scenes[first],
                folders[first]
            );
        }
    }
}

/// A scene's name from the end: a file's stem and then its folders (`.` and `..` left out),
/// or a built-in name (whose dots are no extension: `stress-emissive-box-0.99`).
fn name_parts(scene: &str) -> Vec<String> {
    let path = Path::new(scene);
    let normal = path.components().filter_map(|c| match c {
        Component::Normal(part) => Some(part.to_string_lossy().to_string()),
        _ => None,
    });
    let mut parts: Vec<String> = normal.collect();
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let scene_file = extension.is_some_and(|e| SCENE_FILE_EXTENSIONS.contains(&e.as_str()));
    if let (Some(last), Some(stem), true) = (parts.last_mut(), path.file_stem(), scene_file) {
        *last = stem.to_string_lossy().to_string();
    }
    parts.reverse();
    if parts.is_empty() {
        parts.push(scene.to_string());
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folders(scenes: &[&str]) -> Result<Vec<String>> {
        scene_folders(&scenes.iter().map(|s| s.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn scene_folders_are_names_or_file_stems_told_apart_by_their_folders() {
        let f = folders(&["cornell-diffuse", "scenes/cornell/box.ron", "my scene.gltf"]).unwrap();
        assert_eq!(f, ["cornell-diffuse", "box", "my-scene"]);
        let dotted = folders(&["stress-emissive-box-0.99", "stress-emissive-box-0.999"]).unwrap();
        assert_eq!(dotted, ["stress-emissive-box-0-99", "stress-emissive-box-0-999"]);
        let bitterli = [
            "../shared/bitterli/veach-bidir/scene.xml",
            "../shared/bitterli/modern-hall/scene.xml",
        ];
        assert_eq!(folders(&bitterli).unwrap(), ["veach-bidir-scene", "modern-hall-scene"]);
        let e = folders(&["cornell-diffuse", "x/a.ron", "cornell-diffuse"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("scene 'cornell-diffuse' is named twice"), "{e}");
    }
}
