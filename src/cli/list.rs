//! `lightgraph list`: graphs, scenes (with what each needs from the asset root) and GPU
//! adapters.

use anyhow::Result;
use lightgraph::asset_catalog::{Catalog, Lack};
use lightgraph::assets;
use lightgraph::run::load_graph;
use std::path::Path;

pub fn list() -> Result<()> {
    println!("graphs:");
    for name in assets::graph_names() {
        match load_graph(&name) {
            Ok(g) => println!(
                "  {name}: {} (layouts: {}; default {})",
                g.description,
                g.layouts.keys().cloned().collect::<Vec<_>>().join(", "),
                g.default_layout
            ),
            Err(e) => println!("  {name}: cannot load: {e}"),
        }
    }
    let root = assets::asset_root();
    match &root {
        Some(r) => println!("scenes (asset root {}):", r.display()),
        None => println!("scenes (no asset root: --assets DIR or LIGHTGRAPH_ASSETS):"),
    }
    let catalog = Catalog::builtin();
    for (name, path) in assets::scene_names() {
        println!("  {name} ({path}){}", needs(&path, &catalog, root.as_deref()));
    }
    println!("adapters:");
    let adapters = lightgraph_engine::gpu::adapters();
    if adapters.is_empty() {
        println!("  none: {}", lightgraph_engine::gpu::NO_ADAPTER_HELP);
    }
    for (i, a) in adapters.iter().enumerate() {
        println!("  {}", lightgraph_engine::gpu::describe_adapter(i, a));
    }
    Ok(())
}

/// What the built-in scene at `path` lacks under the asset root and how to get it, as the end
/// of its line: empty when it lacks nothing.
fn needs(path: &str, catalog: &Catalog, root: Option<&Path>) -> String {
    let scene = assets::builtin()
        .read(path)
        .map_err(|e| e.to_string())
        .and_then(|text| lightgraph_scenes::parse_scene(path, &text).map_err(|e| e.to_string()));
    let scene = match scene {
        Ok(scene) => scene,
        Err(e) => return format!(": cannot parse: {e}"),
    };
    let lacks: Vec<String> = catalog
        .lacks(&assets::scene_asset_files(&scene), root)
        .into_iter()
        .map(|lack| match lack {
            Lack::Fetch { asset, bytes } => format!("lightgraph assets fetch {asset} ({})", mib(bytes)),
            Lack::NotDownloadable { asset, bytes } => format!(
                "{asset} ({}), which has no public download (lightgraph assets list says where it comes from)",
                mib(bytes)
            ),
            Lack::Uncatalogued(asset) => format!("{asset}, which the asset catalog does not list"),
        })
        .collect();
    if lacks.is_empty() {
        String::new()
    } else {
        format!(" [needs {}]", lacks.join("; "))
    }
}

/// Bytes in MiB with one decimal.
fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}
