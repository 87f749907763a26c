//! `lightgraph list`: graphs, scenes and GPU adapters.

use anyhow::Result;
use lightgraph::assets;
use lightgraph::run::load_graph;

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
    println!("scenes:");
    for (name, path) in assets::scene_names() {
        println!("  {name} ({path})");
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
