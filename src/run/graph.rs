//! Loading a run's graph: a built-in name or a `.ron` file, its constants' names checked
//! against the flags the host sets, the layout a run names, and whether it handles a scene's
//! features.

use crate::run::options::FLOAT32_ATOMIC_FLAG;
use crate::run::scene::LoadedScene;
use anyhow::{Result, anyhow};
use lightgraph_engine::Graph;
use lightgraph_engine::ir::LayoutDecl;

/// Loads a graph by built-in name or `.ron` path.
pub fn load_graph(name: &str) -> Result<Graph> {
    let (vfs, path) = crate::assets::graph_source(name).map_err(|e| anyhow!(e))?;
    let graph = Graph::load(&vfs, &path)?;
    check_constant_names(&graph)?;
    Ok(graph)
}

/// Every true `Bool` constant of a graph is a preprocessor flag too (docs/graphs.md): one named
/// like a flag the host sets (a scene feature, the BVH's, split geometry's, the device's) would switch that code
/// on or off behind the host's back, so it is an error at its declaration.
fn check_constant_names(graph: &Graph) -> Result<()> {
    let mut host = lightgraph_scenes::features::all();
    host.extend(lightgraph_scenes::bvh::BvhKind::Cwbvh.flag().map(String::from));
    host.insert(FLOAT32_ATOMIC_FLAG.to_string());
    host.insert(lightgraph_scenes::split::FLAG.to_string());
    match graph.declared.constants.keys().find(|k| host.contains(*k)) {
        Some(name) => Err(graph
            .error_at_decl(
                name,
                format!("constant '{name}' has the name of a flag the host sets for the kernels (a scene feature, the BVH's, split geometry's or the device's): rename it"),
            )
            .into()),
        None => Ok(()),
    }
}

/// The layout called `name` (an unknown name is an error listing the graph's layouts), or
/// the graph's default.
pub fn named_layout(graph: &Graph, name: Option<&str>) -> Result<(String, LayoutDecl)> {
    let name = name.unwrap_or(&graph.default_layout);
    Ok((name.to_string(), graph.layout(name)?.clone()))
}

/// Scene features a graph renders only where its coverage says it `handles` them: the
/// feature flag, the word a graph declares, and what the feature is.
const DECLARED_FEATURES: [(&str, &str, &str); 2] = [
    (
        "MEDIA",
        "media",
        "participating media or index-matched (null) boundaries",
    ),
    ("MEDIA_GRID", "media-grid", "heterogeneous media (density grids)"),
];

/// Checks that `graph` handles every feature of `scene` that graphs must declare (coverage's
/// `handles`), naming the feature and the built-in graphs that do.
pub fn graph_handles_scene(graph: &Graph, scene: &LoadedScene) -> Result<(), String> {
    let used = lightgraph_scenes::features::used(&scene.compiled);
    for (flag, word, what) in DECLARED_FEATURES {
        let handles = |g: &Graph| g.declared.file.coverage.handles.iter().any(|h| h == word);
        if used.contains(flag) && !handles(graph) {
            let able: Vec<String> = crate::assets::graph_names()
                .into_iter()
                .filter(|name| load_graph(name).is_ok_and(|g| handles(&g)))
                .collect();
            return Err(format!(
                "graph '{}' does not handle {what}, which the scene has; render it with {} (docs/media.md)",
                graph.declared.file.name,
                able.join(", ")
            ));
        }
    }
    Ok(())
}
