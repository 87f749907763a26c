//! Downloads a catalogued asset's files over HTTP(S) into the asset root, each checked against
//! the catalog's size and SHA-256 before it takes its place: it is written under a temporary
//! name in the root first and renamed only once it verifies, so a failed download leaves
//! nothing behind.

use crate::asset_catalog::{Asset, AssetFile, FileState, HashingWriter, check_file};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What fetching one file did.
#[derive(Debug, PartialEq)]
pub enum Fetched {
    /// Downloaded, verified and put in place.
    Downloaded,
    /// Already there and intact: not downloaded.
    AlreadyIntact,
}

/// Downloads every file of `asset` that has a URL and is not already intact under `root`
/// (created if need be), calling `progress` with each file's path and what was done. Stops at
/// the first file that cannot be downloaded or does not verify, with an error naming the file,
/// its URL and the problem.
pub fn fetch_asset(asset: &Asset, root: &Path, progress: &mut dyn FnMut(&str, Fetched)) -> Result<(), String> {
    if asset.downloadable().next().is_none() {
        return Err(format!(
            "asset {} has no public download: {}",
            asset.name,
            asset
                .not_downloadable
                .as_deref()
                .unwrap_or("no file of it has a URL in the catalog")
        ));
    }
    std::fs::create_dir_all(root).map_err(|e| format!("asset root {}: {e}", root.display()))?;
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_connect(Some(Duration::from_secs(30)))
        .timeout_recv_body(Some(Duration::from_secs(60)))
        .build()
        .into();
    for (file, url) in asset.downloadable() {
        let destination = file.location(root, asset);
        if check_file(&destination, file)? == FileState::Intact {
            progress(&file.path, Fetched::AlreadyIntact);
            continue;
        }
        let temporary = root.join(format!(".lightgraph-fetch-{}.part", std::process::id()));
        let result = download_verified(&agent, url, file, &temporary)
            .map_err(|e| format!("asset {} file {}: {e}", asset.name, file.path))
            .and_then(|()| put_in_place(&temporary, &destination));
        if result.is_err() {
            let _ = std::fs::remove_file(&temporary);
        }
        result?;
        progress(&file.path, Fetched::Downloaded);
    }
    Ok(())
}

/// Downloads `url` into `temporary`, then checks its size and SHA-256 against `file`.
fn download_verified(agent: &ureq::Agent, url: &str, file: &AssetFile, temporary: &Path) -> Result<(), String> {
    let mut response = agent.get(url).call().map_err(|e| match e {
        ureq::Error::StatusCode(code) => format!("could not download {url}: the server answered HTTP {code}"),
        e => format!("could not download {url}: {e} (is the network reachable from here?)"),
    })?;
    let out = std::fs::File::create(temporary).map_err(|e| format!("{}: {e}", temporary.display()))?;
    let mut hashing = HashingWriter::new(std::io::BufWriter::new(out));
    // One byte over the catalog's size is enough to tell that it differs.
    let mut body = response.body_mut().with_config().limit(file.size + 1).reader();
    std::io::copy(&mut body, &mut hashing).map_err(|e| format!("download of {url} failed: {e}"))?;
    let (mut out, (size, sha256)) = hashing.finish();
    out.flush().map_err(|e| format!("{}: {e}", temporary.display()))?;
    if size != file.size || sha256 != file.sha256 {
        return Err(format!(
            "{url} gave {size} bytes with SHA-256 {sha256}, the catalog says {} bytes with SHA-256 {}: not written",
            file.size, file.sha256
        ));
    }
    Ok(())
}

/// Moves a verified download to its place, creating its folders.
fn put_in_place(temporary: &Path, destination: &PathBuf) -> Result<(), String> {
    if let Some(folder) = destination.parent() {
        std::fs::create_dir_all(folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    }
    std::fs::rename(temporary, destination).map_err(|e| format!("{}: {e}", destination.display()))
}
