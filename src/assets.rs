//! Where graphs, passes, shaders and scenes come from: the files built into the binary,
//! with a user's folders searched first.

use lightgraph_engine::{Layer, Vfs};
use std::path::Path;

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/embedded.rs"));
}

/// The built-in files.
pub fn builtin() -> Vfs {
    Vfs::new(vec![Layer::Embedded(embedded::FILES)])
}

/// The bytes of the built-in binary file at `virtual_path` (a built-in scene's density grid).
pub fn builtin_binary(virtual_path: &str) -> Option<&'static [u8]> {
    embedded::BINARY_FILES
        .iter()
        .find(|(p, _)| *p == virtual_path)
        .map(|(_, bytes)| *bytes)
}

/// A file a scene names (a density grid), relative to the scene file `scene_file`: on disk
/// beside it, else built in beside a built-in scene.
pub fn scene_relative_file(scene_file: &str, name: &str) -> Result<Vec<u8>, String> {
    let dir = Path::new(scene_file).parent().unwrap_or(Path::new(""));
    let path = dir.join(name);
    if path.is_file() {
        return std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()));
    }
    let virtual_path = path.to_string_lossy().replace('\\', "/");
    builtin_binary(&virtual_path)
        .map(<[u8]>::to_vec)
        .ok_or_else(|| format!("{} not found (it is read relative to the scene file)", path.display()))
}

/// A graph given on the command line: a built-in name (`pt`) or a `.ron` file on disk, whose
/// folder is searched first for the files it names. Returns the file system and the virtual
/// path of the graph.
pub fn graph_source(graph: &str) -> Result<(Vfs, String), String> {
    let vfs = builtin();
    let path = Path::new(graph);
    if graph.ends_with(".ron") && path.is_file() {
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let name = path
            .file_name()
            .expect("a file has a name")
            .to_string_lossy()
            .to_string();
        return Ok((vfs.with_front(Layer::Dir(dir.to_path_buf())), name));
    }
    let virtual_path = format!("graphs/{graph}.ron");
    if vfs.exists(&virtual_path) {
        return Ok((vfs, virtual_path));
    }
    Err(format!(
        "graph '{graph}' not found: it is neither a .ron file nor a built-in graph (built-in: {})",
        graph_names().join(", ")
    ))
}

/// Names of the built-in graphs.
pub fn graph_names() -> Vec<String> {
    builtin()
        .list("graphs", ".ron")
        .iter()
        .map(|p| p.trim_start_matches("graphs/").trim_end_matches(".ron").to_string())
        .collect()
}

/// Built-in scenes: (name, virtual path), from every folder under `scenes/`.
pub fn scene_names() -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = embedded::FILES
        .iter()
        .filter(|(p, _)| p.starts_with("scenes/") && p.ends_with(".ron"))
        .map(|(p, _)| {
            (
                p.rsplit('/').next().unwrap_or(p).trim_end_matches(".ron").to_string(),
                p.to_string(),
            )
        })
        .collect();
    out.sort();
    out
}

/// The folder scene files find their assets in: `LIGHTGRAPH_ASSETS` (what `--assets` sets),
/// else `../shared/scenes` from the current folder or from the repository lightgraph was
/// built from, when it exists.
pub fn asset_root() -> Option<std::path::PathBuf> {
    if let Some(dir) = std::env::var_os("LIGHTGRAPH_ASSETS") {
        return Some(dir.into());
    }
    let candidates = [
        Path::new("../shared/scenes").to_path_buf(),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes"),
    ];
    candidates.into_iter().find(|d| d.is_dir())
}

/// The files below the asset root that `scene` reads: its glTF asset or Mitsuba file (whose
/// own files lie beside it) and its environment maps.
pub fn scene_asset_files(scene: &lightgraph_scenes::model::Scene) -> Vec<String> {
    let maps = scene.lights.iter().filter_map(|l| match l {
        lightgraph_scenes::model::Light::Environment { file, .. } => Some(file.clone()),
        _ => None,
    });
    scene.gltf.iter().chain(&scene.mitsuba).cloned().chain(maps).collect()
}

/// The text of a scene given by built-in name or path, with the name errors should use.
pub fn scene_text(scene: &str) -> Result<(String, String), String> {
    let path = Path::new(scene);
    if path.is_file() {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{scene}: {e}"))?;
        return Ok((scene.to_string(), text));
    }
    if let Some((_, virtual_path)) = scene_names().into_iter().find(|(n, _)| n == scene) {
        return Ok((
            virtual_path.clone(),
            builtin().read(&virtual_path).map_err(|e| e.to_string())?,
        ));
    }
    let names: Vec<String> = scene_names().into_iter().map(|(n, _)| n).collect();
    Err(format!(
        "scene '{scene}' not found: no such file, and not a built-in scene (built-in: {})",
        names.join(", ")
    ))
}
