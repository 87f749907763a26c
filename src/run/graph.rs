//! Loading a run's graph: a built-in name or a `.ron` file, its constants' names checked
//! against the flags the host sets, and the layout a run names.

use crate::run::options::FLOAT32_ATOMIC_FLAG;
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
