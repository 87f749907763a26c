//! `lightgraph assets list|check|fetch`: which catalogued assets (`scenes/assets.toml`) an asset
//! root holds, whether they are intact, and downloading those that have a public source.

use anyhow::{Result, anyhow, bail};
use clap::{Args, Subcommand};
use lightgraph::asset_catalog::{Asset, AssetState, Catalog, check_asset};
use lightgraph::fetch::{Fetched, fetch_asset};
use std::path::{Path, PathBuf};

/// `lightgraph assets`: the catalog's assets against an asset root.
#[derive(Args)]
pub struct AssetsArgs {
    /// What to do.
    #[command(subcommand)]
    pub action: AssetsAction,
    /// Read this catalog instead of the built-in one (scenes/assets.toml).
    #[arg(long, global = true, value_name = "FILE")]
    pub catalog: Option<PathBuf>,
}

/// The actions of `lightgraph assets`.
#[derive(Subcommand)]
pub enum AssetsAction {
    /// List every asset: what it is, its licence and source, whether it can be downloaded, and
    /// whether its files are under the asset root (by name and size; `check` reads them).
    List {
        /// The asset root (default: LIGHTGRAPH_ASSETS, else the developers' shared scenes
        /// beside a checkout, where they exist).
        #[arg(long)]
        root: Option<PathBuf>,
    },
    /// Check every asset's files under DIR against the catalog's sizes and SHA-256s: intact,
    /// missing, partial or damaged; fails when a file present differs.
    Check {
        /// The asset root (default: LIGHTGRAPH_ASSETS, else the developers' shared scenes
        /// beside a checkout, where they exist).
        dir: Option<PathBuf>,
    },
    /// Download an asset's files from their public sources into DIR/NAME, each verified
    /// against the catalog before it is put in place.
    Fetch {
        /// The asset (a folder name, as `lightgraph assets list` shows).
        name: String,
        /// The asset root to write into (default: LIGHTGRAPH_ASSETS, else the developers'
        /// shared scenes beside a checkout, where they exist).
        #[arg(long, value_name = "DIR")]
        to: Option<PathBuf>,
    },
}

/// Runs `lightgraph assets`.
pub fn assets(args: AssetsArgs) -> Result<()> {
    let catalog = match &args.catalog {
        Some(file) => Catalog::load(file).map_err(|e| anyhow!(e))?,
        None => Catalog::builtin(),
    };
    match args.action {
        AssetsAction::List { root } => list(&catalog, root.or_else(lightgraph::assets::asset_root).as_deref()),
        AssetsAction::Check { dir } => check(&catalog, &root_or_error(dir, "DIR")?),
        AssetsAction::Fetch { name, to } => fetch(&catalog, &name, &root_or_error(to, "--to DIR")?),
    }
}

/// The folder given, else the asset root, else an error saying where the root is looked for.
fn root_or_error(given: Option<PathBuf>, option: &str) -> Result<PathBuf> {
    given.or_else(lightgraph::assets::asset_root).ok_or_else(|| {
        anyhow!("no asset root: pass {option} or set LIGHTGRAPH_ASSETS (../shared/scenes, the default, does not exist)")
    })
}

fn list(catalog: &Catalog, root: Option<&Path>) -> Result<()> {
    match root {
        Some(r) => println!("asset root: {}", r.display()),
        None => println!("asset root: none (--root DIR, LIGHTGRAPH_ASSETS, or ../shared/scenes)"),
    }
    for asset in &catalog.assets {
        let present = root.map_or(0, |r| {
            let sized = |f: &&lightgraph::asset_catalog::AssetFile| {
                std::fs::metadata(f.location(r, asset)).is_ok_and(|m| m.len() == f.size)
            };
            asset.files.iter().filter(sized).count()
        });
        println!(
            "{}: {} ({} files, {}; {} of them here)",
            asset.name,
            asset.what,
            asset.files.len(),
            mib(asset.size()),
            present
        );
        println!("  licence: {}", asset.licence);
        println!("  source: {}", asset.source);
        println!("  download: {}", download_line(asset));
    }
    Ok(())
}

/// How much of an asset `fetch` can download.
fn download_line(asset: &Asset) -> String {
    let downloadable = asset.downloadable().count();
    match &asset.not_downloadable {
        None => format!("every file (lightgraph assets fetch {})", asset.name),
        Some(why) if downloadable == 0 => format!("none: {why}"),
        Some(why) => format!(
            "{downloadable} of {} files (lightgraph assets fetch {}); {why}",
            asset.files.len(),
            asset.name
        ),
    }
}

fn mib(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}

fn check(catalog: &Catalog, root: &Path) -> Result<()> {
    println!("asset root: {}", root.display());
    let (mut intact, mut damaged) = (0, 0);
    for asset in &catalog.assets {
        let line = match check_asset(asset, root).map_err(|e| anyhow!(e))? {
            AssetState::Intact => {
                intact += 1;
                format!("intact ({} files)", asset.files.len())
            }
            AssetState::Missing => format!("missing ({})", download_line(asset)),
            AssetState::Partial(absent) => format!(
                "partial: {} of {} files absent: {}",
                absent.len(),
                asset.files.len(),
                absent.join(", ")
            ),
            AssetState::Damaged(files) => {
                damaged += 1;
                let list: Vec<String> = files.iter().map(|(p, why)| format!("{p}: {why}")).collect();
                format!("DAMAGED: {}", list.join("; "))
            }
        };
        println!("{:<28} {line}", asset.name);
    }
    println!(
        "{intact} of {} assets intact under {}",
        catalog.assets.len(),
        root.display()
    );
    if damaged > 0 {
        bail!(
            "{damaged} asset(s) under {} differ from the catalog (see above): replace the damaged files (lightgraph assets fetch NAME --to DIR where the asset has a download)",
            root.display()
        );
    }
    Ok(())
}

fn fetch(catalog: &Catalog, name: &str, root: &Path) -> Result<()> {
    let asset = catalog.find(name).map_err(|e| anyhow!(e))?;
    let mut report = |path: &str, what: Fetched| match what {
        Fetched::Downloaded => eprintln!("{name}/{path}: downloaded and verified"),
        Fetched::AlreadyIntact => eprintln!("{name}/{path}: already intact"),
    };
    fetch_asset(asset, root, &mut report).map_err(|e| anyhow!(e))?;
    match &asset.not_downloadable {
        Some(why) => println!(
            "{name}: every downloadable file is in {} ({why})",
            root.join(name).display()
        ),
        None => println!("{name}: intact in {}", root.join(name).display()),
    }
    Ok(())
}
