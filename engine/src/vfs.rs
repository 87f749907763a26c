//! A layered, read-only file system for graphs, pass catalogs and WGSL sources.
//!
//! Files are named by forward-slash paths such as `graphs/pt.ron` or `shaders/lib/rng.wgsl`.
//! Layers are searched in order: directories on disk first (a user's own graph folder),
//! then files embedded in the binary, so a graph shipped with the tool and a graph written by
//! a user resolve their WGSL the same way.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// One place files are looked up in.
#[derive(Debug, Clone)]
pub enum Layer {
    /// A directory on disk; a virtual path `a/b` maps to `dir/a/b`.
    Dir(PathBuf),
    /// Files compiled into the binary: `(virtual path, contents)`.
    Embedded(&'static [(&'static str, &'static str)]),
}

/// The layered file system.
#[derive(Debug, Clone, Default)]
pub struct Vfs {
    layers: Vec<Layer>,
}

impl Vfs {
    /// A file system made of `layers`, searched in order.
    pub fn new(layers: Vec<Layer>) -> Self {
        Vfs { layers }
    }

    /// A copy with `layer` searched before all others.
    pub fn with_front(&self, layer: Layer) -> Self {
        let mut layers = vec![layer];
        layers.extend(self.layers.iter().cloned());
        Vfs { layers }
    }

    /// Reads the file at virtual path `path`.
    pub fn read(&self, path: &str) -> Result<String> {
        for layer in &self.layers {
            match layer {
                Layer::Dir(dir) => {
                    let full = dir.join(path);
                    if full.is_file() {
                        return std::fs::read_to_string(&full).map_err(|e| Error::Io {
                            path: full.clone(),
                            message: e.to_string(),
                        });
                    }
                }
                Layer::Embedded(files) => {
                    if let Some((_, text)) = files.iter().find(|(p, _)| *p == path) {
                        return Ok((*text).to_string());
                    }
                }
            }
        }
        Err(Error::Io {
            path: PathBuf::from(path),
            message: format!("not found (looked in {})", self.describe()),
        })
    }

    /// Whether `path` exists in any layer.
    pub fn exists(&self, path: &str) -> bool {
        self.layers.iter().any(|layer| match layer {
            Layer::Dir(dir) => dir.join(path).is_file(),
            Layer::Embedded(files) => files.iter().any(|(p, _)| *p == path),
        })
    }

    /// All files under the virtual directory `dir` whose names end with `suffix`, sorted and
    /// without duplicates (an earlier layer hides a later one).
    pub fn list(&self, dir: &str, suffix: &str) -> Vec<String> {
        let prefix = format!("{}/", dir.trim_end_matches('/'));
        let mut out: Vec<String> = Vec::new();
        for layer in &self.layers {
            match layer {
                Layer::Dir(root) => {
                    if let Ok(entries) = std::fs::read_dir(root.join(dir)) {
                        for entry in entries.flatten() {
                            let name = entry.file_name().to_string_lossy().to_string();
                            if name.ends_with(suffix) && entry.path().is_file() {
                                out.push(format!("{prefix}{name}"));
                            }
                        }
                    }
                }
                Layer::Embedded(files) => {
                    for (p, _) in files.iter() {
                        if let Some(rest) = p.strip_prefix(&prefix)
                            && !rest.contains('/')
                            && rest.ends_with(suffix)
                        {
                            out.push((*p).to_string());
                        }
                    }
                }
            }
        }
        out.sort();
        out.dedup();
        out
    }

    /// A short description of the layers, for error messages.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self
            .layers
            .iter()
            .map(|l| match l {
                Layer::Dir(d) => d.display().to_string(),
                Layer::Embedded(_) => "the files built into lightgraph".to_string(),
            })
            .collect();
        parts.join(", ")
    }
}

/// The virtual path of `file` relative to `base`, with forward slashes, if it lies below it.
pub fn relative_virtual_path(base: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(base).ok()?;
    Some(
        rel.components()
            .map(|c| c.as_os_str().to_string_lossy().to_string())
            .collect::<Vec<_>>()
            .join("/"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    static FILES: &[(&str, &str)] = &[
        ("graphs/a.ron", "A"),
        ("graphs/sub/b.ron", "B"),
        ("shaders/x.wgsl", "X"),
    ];

    #[test]
    fn embedded_lookup_and_listing() {
        let vfs = Vfs::new(vec![Layer::Embedded(FILES)]);
        assert_eq!(vfs.read("shaders/x.wgsl").unwrap(), "X");
        assert!(vfs.read("shaders/y.wgsl").is_err());
        assert_eq!(vfs.list("graphs", ".ron"), vec!["graphs/a.ron".to_string()]);
    }

    #[test]
    fn directories_hide_embedded_files() {
        let dir = std::env::temp_dir().join(format!("lg-vfs-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("shaders")).unwrap();
        std::fs::write(dir.join("shaders/x.wgsl"), "disk").unwrap();
        let vfs = Vfs::new(vec![Layer::Dir(dir.clone()), Layer::Embedded(FILES)]);
        assert_eq!(vfs.read("shaders/x.wgsl").unwrap(), "disk");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
