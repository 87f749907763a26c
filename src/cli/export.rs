//! `lightgraph export`: a scene written in another renderer's format (Mitsuba 3), to render
//! the same scene there (bench/peers/).

use super::args::parse_resolution;
use anyhow::{Result, anyhow};
use clap::{Args, ValueEnum};
use lightgraph::run::DEFAULT_SCENE;
use std::path::PathBuf;

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
    /// The folder to write (created; files of the same names are replaced).
    #[arg(long)]
    pub out: PathBuf,
}

/// Writes the scene in the chosen format and prints what renders differently there.
pub fn export(a: ExportArgs) -> Result<()> {
    let name = a.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let loaded = lightgraph::run::load_scene(name)?;
    let size = a.res.unwrap_or(loaded.scene.resolution);
    let ExportFormat::Mitsuba = a.format;
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
