//! The layouts `--layout auto` measured fastest, kept on disk: one entry per graph, scene, image
//! size, samples a frame, BVH, constants, adapter and lightgraph version, with the layout
//! itself (kernels and options, as the tuner built it), its rate and when it was measured. A
//! render without `--layout` and a later `--layout auto` of the same key take the entry
//! instead of measuring again. The file is `layouts.ron` in `LIGHTGRAPH_CACHE`, else in
//! `$XDG_CACHE_HOME/lightgraph`, else in `~/.cache/lightgraph`.

use anyhow::{Context, Result};
use lightgraph_engine::ir::LayoutDecl;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// What a measurement holds for: a render with another key measures anew.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Key {
    /// The graph as named on the command line (built-in name or file).
    pub graph: String,
    /// The scene as named on the command line.
    pub scene: String,
    /// Image width and height.
    pub size: (u32, u32),
    /// Samples per pixel a frame.
    pub spp: u32,
    /// The BVH the render asks for: `auto` (the layout's choice) or the one `--bvh` names.
    pub bvh: String,
    /// The constants the render sets (the scene's and `--set`'s), as text.
    pub constants: BTreeMap<String, String>,
    /// The adapter (name, backend, type, driver).
    pub adapter: String,
    /// The lightgraph version that measured.
    pub version: String,
}

/// A measured layout.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Entry {
    /// What it holds for.
    pub key: Key,
    /// The tuner's name for the layout (passes per kernel, loop mode, options).
    pub name: String,
    /// The layout.
    pub layout: LayoutDecl,
    /// Samples per second it rendered when measured.
    pub samples_per_second: f64,
    /// When it was measured (RFC 3339, UTC).
    pub measured: String,
    /// The BVH it was measured with (`cwbvh`, `bvh2`), which a render taking it builds; none in
    /// entries written before it was recorded.
    #[serde(default)]
    pub bvh: Option<String>,
}

/// The cache file.
pub fn path() -> Option<PathBuf> {
    let dir = std::env::var_os("LIGHTGRAPH_CACHE")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("XDG_CACHE_HOME").map(|d| PathBuf::from(d).join("lightgraph")))
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/lightgraph")))?;
    Some(dir.join("layouts.ron"))
}

/// Every entry of the cache file (none when it does not exist); an unreadable file is an
/// error naming it.
fn entries() -> Result<Vec<Entry>> {
    let Some(path) = path() else { return Ok(Vec::new()) };
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read the layout cache", path.display())),
    };
    ron::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}:{}:{}: the layout cache is not valid: {} (the next --layout auto replaces it)",
            path.display(),
            e.span.start.line,
            e.span.start.col,
            e.code
        )
    })
}

/// The entry for `key`, if the cache has one; a cache that cannot be read is a warning
/// (and no entry), never the render's end.
pub fn find(key: &Key) -> Option<Entry> {
    match entries() {
        Ok(all) => all.into_iter().find(|e| &e.key == key),
        Err(e) => {
            eprintln!("warning: {e:#}");
            None
        }
    }
}

/// Stores `entry` in the cache, in place of an entry of the same key (a file that cannot be
/// read is replaced); returns the file.
pub fn store(entry: Entry) -> Result<PathBuf> {
    let path = path().context("no cache folder: set LIGHTGRAPH_CACHE, XDG_CACHE_HOME or HOME")?;
    let mut all = entries().unwrap_or_default();
    all.retain(|e| e.key != entry.key);
    all.push(entry);
    let text = ron::ser::to_string_pretty(&all, ron::ser::PrettyConfig::default())?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create the cache folder", dir.display()))?;
    }
    // Written beside and renamed, so that a reader never sees half a file.
    let partial = path.with_extension("ron.partial");
    std::fs::write(&partial, text).with_context(|| format!("{}: cannot write", partial.display()))?;
    std::fs::rename(&partial, &path).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(path)
}

/// Now, as RFC 3339 in UTC (seconds).
pub fn now() -> String {
    humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string()
}
