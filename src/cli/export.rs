//! `lightgraph export`: a scene written in another renderer's format (Mitsuba 3), to render
//! the same scene there (bench/peers/).

use super::args::parse_resolution;
use anyhow::{Context, Result, anyhow};
use clap::{Args, ValueEnum};
use lightgraph::output::{Output, check_outputs};
use lightgraph::run::DEFAULT_SCENE;
use std::path::{Path, PathBuf};

/// The formats `export` writes.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ExportFormat {
    /// Mitsuba 3: scene.xml, meshes/*.ply, textures/*.png.
    Mitsuba,
}

/// Arguments of `lightgraph export`.
#[derive(Args)]
pub struct ExportArgs {
    /// The format to write.
    #[arg(long, value_enum, default_value = "mitsuba")]
    pub format: ExportFormat,
    /// Scene: a built-in name, a .ron scene file, a bare .gltf/.glb file or a Mitsuba .xml
    /// [default: cornell-mitsuba].
    #[arg(long)]
    pub scene: Option<String>,
    /// Image size WxH of the exported film (default: the scene's).
    #[arg(long, value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Folder scene files find their glTF assets in (also LIGHTGRAPH_ASSETS).
    #[arg(long, env = "LIGHTGRAPH_ASSETS")]
    pub assets: Option<PathBuf>,
    /// The folder to write (created): scene.xml, meshes/ and textures/. A folder holding any
    /// of those is refused unless --force.
    #[arg(long)]
    pub out: PathBuf,
    /// Write into a folder that holds an earlier export: its scene.xml, meshes/ and textures/
    /// are removed first (so that no stale mesh stays); other files there are left alone.
    #[arg(long)]
    pub force: bool,
}

/// What an export writes into its folder.
const EXPORT_ENTRIES: [&str; 3] = ["scene.xml", "meshes", "textures"];

/// Removes an earlier export's entries from `dir` (after --force allowed it).
fn clear_earlier_export(dir: &Path) -> Result<()> {
    for entry in EXPORT_ENTRIES {
        let path = dir.join(entry);
        let removed = match path.is_dir() {
            true => std::fs::remove_dir_all(&path),
            false if path.exists() => std::fs::remove_file(&path),
            false => Ok(()),
        };
        removed.with_context(|| format!("--force: removing {}", path.display()))?;
    }
    Ok(())
}

/// Writes the scene in the chosen format and prints what renders differently there.
pub fn export(a: ExportArgs) -> Result<()> {
    let name = a.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    check_outputs(&[Output::Folder(&a.out, &EXPORT_ENTRIES)], a.force, None)?;
    let loaded = lightgraph::run::load_scene(name)?;
    let size = a.res.unwrap_or(loaded.scene.resolution);
    let ExportFormat::Mitsuba = a.format;
    clear_earlier_export(&a.out)?;
    let notes = lightgraph_scenes::mitsuba::export::write(&loaded.scene, size, &a.out)
        .map_err(|e| anyhow!("{name}: export to {}: {e}", a.out.display()))?;
    for note in &notes {
        eprintln!("note: {note}");
    }
    println!(
        "{}: {} shapes, {} materials written to {}",
        name,
        loaded.scene.shapes.len(),
        loaded.scene.materials.len(),
        a.out.join("scene.xml").display()
    );
    Ok(())
}
