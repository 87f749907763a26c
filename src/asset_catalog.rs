//! The asset catalog (`scenes/assets.toml`, built into the binary): where each asset under the
//! asset root comes from, and the size and SHA-256 of each of its files; and the check of a
//! folder against it.

use serde::Deserialize;
use sha2::{Digest, Sha256};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The catalog built into the binary.
const BUILTIN: &str = include_str!("../scenes/assets.toml");

/// Every catalogued asset.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Catalog {
    /// The assets, one per folder under the asset root.
    #[serde(rename = "asset")]
    pub assets: Vec<Asset>,
}

/// One asset: a folder under the asset root.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Asset {
    /// The folder under the asset root, also the name `lightgraph assets fetch` takes.
    pub name: String,
    /// What it is and which scenes use it.
    pub what: String,
    /// Its licence.
    pub licence: String,
    /// Where it comes from (repository, commit, path), as its SOURCE.md says.
    pub source: String,
    /// Which files no public URL gives, and why; absent when every file has a URL.
    pub not_downloadable: Option<String>,
    /// Its files.
    pub files: Vec<AssetFile>,
}

/// One file of an asset.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AssetFile {
    /// The path below the asset's folder, `/`-separated.
    pub path: String,
    /// Its size in bytes.
    pub size: u64,
    /// Its SHA-256, lower-case hex.
    pub sha256: String,
    /// A public download of exactly these bytes, if there is one.
    pub url: Option<String>,
}

impl Catalog {
    /// The catalog built into the binary.
    pub fn builtin() -> Catalog {
        Catalog::parse(BUILTIN, "scenes/assets.toml").expect("the built-in catalog parses (tested)")
    }

    /// The catalog in `file`; errors name the file.
    pub fn load(file: &Path) -> Result<Catalog, String> {
        let text = std::fs::read_to_string(file).map_err(|e| format!("catalog {}: {e}", file.display()))?;
        Catalog::parse(&text, &file.display().to_string())
    }

    /// Parses a catalog's text; `name` is the file errors name.
    pub fn parse(text: &str, name: &str) -> Result<Catalog, String> {
        let catalog: Catalog = toml::from_str(text)
            .map_err(|e| format!("catalog {name}: {}", e.to_string().trim_end().replace('\n', " ")))?;
        for asset in &catalog.assets {
            if !is_plain_name(&asset.name) {
                return Err(format!(
                    "catalog {name}: asset name '{}' is not a plain folder name",
                    asset.name
                ));
            }
            for file in &asset.files {
                if !file.path.split('/').all(is_plain_name) {
                    return Err(format!(
                        "catalog {name}: asset {}: file path '{}' is not a plain relative path",
                        asset.name, file.path
                    ));
                }
            }
        }
        Ok(catalog)
    }

    /// The asset called `name`; the error lists the names there are.
    pub fn find(&self, name: &str) -> Result<&Asset, String> {
        self.assets.iter().find(|a| a.name == name).ok_or_else(|| {
            let names: Vec<&str> = self.assets.iter().map(|a| a.name.as_str()).collect();
            format!("no asset '{name}' in the catalog (assets: {})", names.join(", "))
        })
    }
}

impl Asset {
    /// The files a public URL gives.
    pub fn downloadable(&self) -> impl Iterator<Item = (&AssetFile, &str)> {
        self.files.iter().filter_map(|f| f.url.as_deref().map(|u| (f, u)))
    }

    /// The sum of its files' sizes in bytes.
    pub fn size(&self) -> u64 {
        self.files.iter().map(|f| f.size).sum()
    }
}

impl AssetFile {
    /// Where the file lies under the asset root.
    pub fn location(&self, root: &Path, asset: &Asset) -> PathBuf {
        self.path.split('/').fold(root.join(&asset.name), |p, c| p.join(c))
    }
}

/// What a scene lacks of one asset under the asset root, and how to get it.
#[derive(Debug, PartialEq)]
pub enum Lack {
    /// The catalog has no asset of that name (a scene of the user's own).
    Uncatalogued(String),
    /// `lightgraph assets fetch NAME` gets what the scene reads: that many bytes at most.
    Fetch { asset: String, bytes: u64 },
    /// The catalog knows the asset, but a file the scene reads has no public download.
    NotDownloadable { asset: String, bytes: u64 },
}

impl Catalog {
    /// What a scene that reads `files` (paths below the asset root, as
    /// [`crate::assets::scene_asset_files`] gives a scene's) lacks under `root` (None: no
    /// root), per asset: nothing when all is there. A file with a public download counts as
    /// there when every downloadable file of its asset is (a Mitsuba scene reads the meshes
    /// beside it), by size; another file when it exists.
    pub fn lacks(&self, files: &[String], root: Option<&Path>) -> Vec<Lack> {
        let mut lacks: Vec<Lack> = Vec::new();
        for file in files {
            let (name, below) = file.split_once('/').unwrap_or((file.as_str(), ""));
            let exists = |path: &Path| root.is_some_and(|r| r.join(path).is_file());
            let lack = match self.assets.iter().find(|a| a.name == name) {
                None if exists(Path::new(file)) => continue,
                None => Lack::Uncatalogued(name.to_string()),
                Some(asset) if asset.files.iter().any(|f| f.path == below && f.url.is_some()) => {
                    let sized = |f: &AssetFile| {
                        root.is_some_and(|r| std::fs::metadata(f.location(r, asset)).is_ok_and(|m| m.len() == f.size))
                    };
                    if asset.downloadable().all(|(f, _)| sized(f)) {
                        continue;
                    }
                    Lack::Fetch {
                        asset: asset.name.clone(),
                        bytes: asset.downloadable().map(|(f, _)| f.size).sum(),
                    }
                }
                Some(_) if exists(Path::new(file)) => continue,
                Some(asset) => Lack::NotDownloadable {
                    asset: asset.name.clone(),
                    bytes: asset.size(),
                },
            };
            if !lacks.contains(&lack) {
                lacks.push(lack);
            }
        }
        lacks
    }
}

/// What a file under the asset root is, against the catalog.
#[derive(Debug, PartialEq)]
pub enum FileState {
    /// Present, with the catalog's size and SHA-256.
    Intact,
    /// Not there.
    Absent,
    /// Present but different: what differs.
    Damaged(String),
}

/// Checks one file against its catalog entry (reads it whole only when the size agrees).
pub fn check_file(path: &Path, file: &AssetFile) -> Result<FileState, String> {
    let size = match std::fs::metadata(path) {
        Ok(m) => m.len(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(FileState::Absent),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    if size != file.size {
        return Ok(FileState::Damaged(format!(
            "{size} bytes, the catalog says {}",
            file.size
        )));
    }
    let reader = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (_, sha256) = sha256_of(reader).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(if sha256 == file.sha256 {
        FileState::Intact
    } else {
        FileState::Damaged(format!("SHA-256 {sha256}, the catalog says {}", file.sha256))
    })
}

/// The byte count and lower-case hex SHA-256 of everything `reader` gives.
pub fn sha256_of(mut reader: impl Read) -> std::io::Result<(u64, String)> {
    let mut hashing = HashingWriter::new(std::io::sink());
    std::io::copy(&mut reader, &mut hashing)?;
    Ok(hashing.finish().1)
}

/// A writer that passes bytes on and hashes them (SHA-256) and counts them on the way.
pub struct HashingWriter<W> {
    inner: W,
    hasher: Sha256,
    count: u64,
}

impl<W: Write> HashingWriter<W> {
    /// Wraps `inner`.
    pub fn new(inner: W) -> Self {
        HashingWriter {
            inner,
            hasher: Sha256::new(),
            count: 0,
        }
    }

    /// The inner writer, and the byte count and lower-case hex SHA-256 of what was written.
    pub fn finish(self) -> (W, (u64, String)) {
        (self.inner, (self.count, hex(&self.hasher.finalize())))
    }
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.count += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A single path component that stays in its folder.
fn is_plain_name(name: &str) -> bool {
    !(name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\']))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// What an asset under the asset root is, from its files' states.
#[derive(Debug, PartialEq)]
pub enum AssetState {
    /// Every file intact.
    Intact,
    /// No file there.
    Missing,
    /// Some files absent (their paths), the others intact.
    Partial(Vec<String>),
    /// Some files differ: path and what differs, each.
    Damaged(Vec<(String, String)>),
}

/// Checks every file of `asset` under `root`.
pub fn check_asset(asset: &Asset, root: &Path) -> Result<AssetState, String> {
    let (mut absent, mut damaged) = (Vec::new(), Vec::new());
    for file in &asset.files {
        match check_file(&file.location(root, asset), file)? {
            FileState::Intact => {}
            FileState::Absent => absent.push(file.path.clone()),
            FileState::Damaged(why) => damaged.push((file.path.clone(), why)),
        }
    }
    Ok(if !damaged.is_empty() {
        AssetState::Damaged(damaged)
    } else if absent.is_empty() {
        AssetState::Intact
    } else if absent.len() == asset.files.len() {
        AssetState::Missing
    } else {
        AssetState::Partial(absent)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_abc_is_the_standard_test_vector() {
        let (n, h) = sha256_of(&b"abc"[..]).unwrap();
        assert_eq!(n, 3);
        assert_eq!(h, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }

    #[test]
    fn the_builtin_catalog_parses_and_names_each_asset_once() {
        let catalog = Catalog::builtin();
        let mut names: Vec<&str> = catalog.assets.iter().map(|a| a.name.as_str()).collect();
        let count = names.len();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), count, "an asset is named twice");
        for asset in &catalog.assets {
            assert!(!asset.files.is_empty(), "{} has no files", asset.name);
            let all_urls = asset.files.iter().all(|f| f.url.is_some());
            assert_eq!(
                all_urls,
                asset.not_downloadable.is_none(),
                "{}: not_downloadable must say why exactly when a file has no URL",
                asset.name
            );
        }
    }

    #[test]
    fn a_path_leaving_the_folder_is_refused() {
        let text = "[[asset]]\nname = \"a\"\nwhat = \"\"\nlicence = \"\"\nsource = \"\"\nfiles = [{ path = \"../x\", size = 1, sha256 = \"00\" }]\n";
        let e = Catalog::parse(text, "t.toml").unwrap_err();
        assert!(e.contains("t.toml") && e.contains("../x"), "{e}");
    }
}
