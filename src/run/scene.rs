//! Loading a run's scene: a built-in name, a RON scene file, a bare glTF or a Mitsuba file,
//! parsed, validated and compiled (primitives, lights, BVH) for the GPU; the BVH a layout asks
//! for; one load per BVH kind where a command's layouts want several.

use anyhow::{Result, anyhow};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::model::Scene;
use lightgraph_scenes::{CompiledScene, parse_scene};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// A scene loaded, validated and prepared for the GPU.
pub struct LoadedScene {
    /// The name it was asked for by.
    pub name: String,
    /// The scene as written.
    pub scene: Scene,
    /// Flattened primitives, lights and BVH.
    pub compiled: CompiledScene,
    /// Seconds spent loading, BVH included.
    pub load_seconds: f64,
}

/// Loads a built-in scene by name, or a scene file by path, with a BVH2.
pub fn load_scene(name: &str) -> Result<LoadedScene> {
    load_scene_with(name, BvhKind::Bvh2)
}

/// Loads a built-in scene by name, a scene file by path, a bare glTF file (`.gltf`, `.glb`;
/// see [`LoadedScene::from_gltf`]) or a Mitsuba scene file (`.xml`,
/// [`LoadedScene::from_mitsuba`]), with a BVH of `kind`; the glTF assets of scene files come
/// from [`crate::assets::asset_root`].
pub fn load_scene_with(name: &str, kind: BvhKind) -> Result<LoadedScene> {
    check_not_a_folder(name)?;
    let lower = name.to_ascii_lowercase();
    let bare_gltf = (lower.ends_with(".gltf") || lower.ends_with(".glb")) && std::path::Path::new(name).is_file();
    let mitsuba = lower.ends_with(".xml") && std::path::Path::new(name).is_file();
    let (file, mut scene) = if bare_gltf {
        (
            name.to_string(),
            LoadedScene::from_gltf(std::path::Path::new(name), kind)?,
        )
    } else if mitsuba {
        (
            name.to_string(),
            LoadedScene::from_mitsuba(std::path::Path::new(name), kind)?,
        )
    } else {
        let (file, text) = crate::assets::scene_text(name).map_err(|e| anyhow!(e))?;
        let scene = LoadedScene::parse(&file, &text, kind, crate::assets::asset_root().as_deref())?;
        (file, scene)
    };
    scene.name = name.to_string();
    if scene.compiled.clipped_primitives > 0 {
        eprintln!(
            "warning: {file}: {} primitives reach beyond ±{:e}, where the BVH clips them: rays do not find those parts",
            scene.compiled.clipped_primitives,
            lightgraph_scenes::TRACED_EXTENT
        );
    }
    Ok(scene)
}

impl LoadedScene {
    /// Parses, validates and compiles the RON scene `text` (`file` names it in errors) with
    /// a BVH of `kind`, importing its glTF asset from below `assets`.
    pub fn parse(file: &str, text: &str, kind: BvhKind, assets: Option<&std::path::Path>) -> Result<LoadedScene> {
        let start = Instant::now();
        let mut scene = parse_scene(file, text)?;
        lightgraph_scenes::read_grids(&mut scene, file, text, |name| {
            crate::assets::scene_relative_file(file, name)
        })?;
        lightgraph_scenes::resolve_gltf(&mut scene, file, assets)?;
        Self::compile(file.to_string(), scene, kind, start)
    }

    /// Loads the bare glTF file at `path` with a BVH of `kind`: its first camera, else one
    /// framing its bounds, and a constant background when it has no light; says on stderr
    /// which of these defaults it took.
    pub fn from_gltf(path: &std::path::Path, kind: BvhKind) -> Result<LoadedScene> {
        let start = Instant::now();
        check_glb_magic(path)?;
        let (scene, notes) = lightgraph_scenes::scene_from_gltf(path)?;
        for note in notes {
            eprintln!("note: {}: {note}", path.display());
        }
        Self::compile(path.display().to_string(), scene, kind, start)
    }

    /// Loads the Mitsuba scene file at `path` (lightgraph_scenes::mitsuba) with a BVH of
    /// `kind`; its warnings go to stderr.
    pub fn from_mitsuba(path: &std::path::Path, kind: BvhKind) -> Result<LoadedScene> {
        let start = Instant::now();
        let imported = lightgraph_scenes::mitsuba::load(path)?;
        for warning in &imported.warnings {
            eprintln!("warning: {warning}");
        }
        Self::compile(path.display().to_string(), imported.scene, kind, start)
    }

    /// Compiles `scene` (named `file` in errors) with a BVH of `kind`; its load time counts
    /// from `start`.
    fn compile(file: String, scene: Scene, kind: BvhKind, start: Instant) -> Result<LoadedScene> {
        let compiled = CompiledScene::with_bvh(&scene, kind).map_err(|e| anyhow!("{file}: {e}"))?;
        Ok(LoadedScene {
            name: file,
            scene,
            compiled,
            load_seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// Parses a BVH kind: `bvh2` or `cwbvh`.
pub fn parse_bvh(s: &str) -> Result<BvhKind, String> {
    match s.to_lowercase().as_str() {
        "bvh2" => Ok(BvhKind::Bvh2),
        "cwbvh" => Ok(BvhKind::Cwbvh),
        _ => Err(format!("'{s}' is not bvh2 or cwbvh")),
    }
}

/// A run's BVH: a kind, or `auto` (none named): the layout's measured choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhChoice(pub Option<BvhKind>);

impl BvhChoice {
    /// Parses `bvh2`, `cwbvh` or `auto`.
    pub fn parse(s: &str) -> Result<BvhChoice, String> {
        match s.to_lowercase().as_str() {
            "auto" => Ok(BvhChoice(None)),
            _ => parse_bvh(s)
                .map(|k| BvhChoice(Some(k)))
                .map_err(|e| format!("{e} or auto")),
        }
    }

    /// The BVH of a layout: the one named, else the layout's `bvh` hint (graphs/*.ron, from
    /// measurements on an H100: docs/performance.md), else the CWBVH.
    pub fn for_layout(self, name: &str, decl: &LayoutDecl) -> Result<BvhKind> {
        if let Some(kind) = self.0 {
            return Ok(kind);
        }
        match decl.hints.get("bvh") {
            None => Ok(BvhKind::Cwbvh),
            Some(hint) => parse_bvh(hint).map_err(|e| anyhow!("layout '{name}': its hint bvh: {e}")),
        }
    }

    /// The BVH when no layout decides (`--layout auto` measures layouts on one scene).
    pub fn or_default(self) -> BvhKind {
        self.0.unwrap_or(BvhKind::Cwbvh)
    }
}

/// Scenes loaded with each BVH kind asked for, once each (layouts of one command may want
/// different kinds).
pub struct Scenes {
    name: String,
    loaded: Vec<(BvhKind, Arc<LoadedScene>)>,
}

impl Scenes {
    /// None loaded yet of scene `name`.
    pub fn new(name: &str) -> Scenes {
        Scenes {
            name: name.to_string(),
            loaded: Vec::new(),
        }
    }

    /// Loads the scene with the BVH `bvh` gives layout `name` (`decl`), unless it is loaded
    /// already; returns that BVH.
    pub fn load_for(&mut self, bvh: BvhChoice, name: &str, decl: &LayoutDecl) -> Result<BvhKind> {
        let kind = bvh.for_layout(name, decl)?;
        if !self.loaded.iter().any(|(k, _)| *k == kind) {
            self.loaded.push((kind, Arc::new(load_scene_with(&self.name, kind)?)));
        }
        Ok(kind)
    }

    /// The longest time one of the loads took (parsing and the BVH build), in seconds.
    pub fn load_seconds(&self) -> f64 {
        self.loaded.iter().map(|(_, s)| s.load_seconds).fold(0.0, f64::max)
    }

    /// The scene with `kind`, which [`Scenes::load_for`] loaded.
    pub fn get(&self, kind: BvhKind) -> &LoadedScene {
        self.entry(kind)
    }

    /// The scene with `kind`, which [`Scenes::load_for`] loaded, shared (for a
    /// [`crate::run::Run`]).
    pub fn shared(&self, kind: BvhKind) -> Arc<LoadedScene> {
        Arc::clone(self.entry(kind))
    }

    fn entry(&self, kind: BvhKind) -> &Arc<LoadedScene> {
        &self
            .loaded
            .iter()
            .find(|(k, _)| *k == kind)
            .expect("loaded before use")
            .1
    }
}

/// Checks that `scene` (named by option `flag`) is a file or a built-in scene (loading it, and
/// the errors of its content, come in its turn).
pub fn find_scene(scene: &str, flag: &str) -> Result<()> {
    check_not_a_folder(scene).map_err(|e| anyhow!("{flag}: {e}"))?;
    if !Path::new(scene).is_file() {
        crate::assets::scene_text(scene).map_err(|e| anyhow!("{flag}: {e}"))?;
    }
    Ok(())
}

/// An error where the scene `name` is a folder, which no scene is.
fn check_not_a_folder(name: &str) -> Result<()> {
    if Path::new(name).is_dir() {
        return Err(anyhow!(
            "{name} is a folder, not a scene: give a built-in scene's name (see `lightgraph list`), a .ron scene \
             file, a .gltf/.glb file or a Mitsuba .xml file"
        ));
    }
    Ok(())
}

/// An error naming the file where a `.glb` does not begin with the glTF binary's magic
/// (`glTF`), instead of the JSON parser's error of its first bytes.
fn check_glb_magic(path: &Path) -> Result<()> {
    use std::io::Read;
    let is_glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let mut magic = [0u8; 4];
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut magic));
    if is_glb && (read.is_err() || &magic != b"glTF") {
        return Err(anyhow!(
            "{}: not a valid glTF binary (.glb): it does not begin with 'glTF'",
            path.display()
        ));
    }
    Ok(())
}
