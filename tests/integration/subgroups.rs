//! Queue and compaction appends aggregated per subgroup (the adapter has subgroups: lavapipe
//! runs 8 lanes) against one atomic per item (`--no-subgroups`): every layout that appends
//! renders the same image with one seed, to float rounding. The slots items land in change,
//! so which thread runs an item and the order of the film's atomic additions change; but each
//! item carries its own pixel, sample and random stream, so the same rays are traced (equal
//! counters) and the same contributions are summed in another order.

use crate::cli::{lightgraph, temp_dir};
use crate::common::{assert_same_render, gpu, render_with_layout};
use lightgraph::run::{LayoutOverrides, load_graph, load_scene};
use lightgraph_engine::Plan;

/// The layouts of `graph` whose kernels append: to a queue, or to a compaction boundary.
fn appending_layouts(graph: &str) -> Vec<String> {
    let loaded = load_graph(graph).unwrap();
    loaded
        .layouts
        .keys()
        .filter(|name| {
            let plan = Plan::new(&loaded, name).unwrap();
            !plan.queued_streams.is_empty() || !plan.boundaries.is_empty()
        })
        .cloned()
        .collect()
}

#[test]
fn subgroup_appends_render_what_per_item_appends_render() {
    if !gpu().target().subgroups() {
        eprintln!("the adapter has no subgroups: both runs append per item");
    }
    let scene = load_scene("cornell-glossy-point").unwrap();
    for graph in ["pt", "lt", "bpt-naive", "bpt-streaming"] {
        let layouts = appending_layouts(graph);
        assert!(!layouts.is_empty(), "{graph} has layouts with queues or compaction");
        for layout in &layouts {
            let run = |no_subgroups: bool| {
                let overrides = LayoutOverrides {
                    no_subgroups,
                    ..Default::default()
                };
                render_with_layout(&scene, graph, layout, (16, 16), 2, 2, 42, &[], overrides)
            };
            assert_same_render(&run(false), &run(true), &format!("{graph} {layout}"));
        }
    }
}

/// The WGSL `explain --wgsl` writes for WavefrontPT, with `extra` flags, joined.
fn wavefront_wgsl(extra: &[&str]) -> String {
    let dir = temp_dir(&format!("subgroups{}", extra.len()));
    let dir_arg = dir.to_str().unwrap();
    let mut args = vec!["explain", "--graph", "pt", "--layout", "WavefrontPT", "--res", "16x16"];
    args.extend(["--wgsl", dir_arg]);
    args.extend(extra);
    let out = lightgraph(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut text = String::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        text.push_str(&std::fs::read_to_string(entry.unwrap().path()).unwrap());
    }
    text
}

#[test]
fn no_subgroups_takes_the_subgroup_operations_out_of_the_kernels() {
    let with = wavefront_wgsl(&[]);
    assert!(with.contains("atomicAdd"), "WavefrontPT appends to queues");
    assert_eq!(
        with.contains("subgroupExclusiveAdd"),
        gpu().target().subgroups(),
        "appends aggregate per subgroup exactly where the adapter has subgroups"
    );
    let without = wavefront_wgsl(&["--no-subgroups"]);
    assert!(
        !without.contains("subgroup"),
        "--no-subgroups leaves subgroup operations"
    );
}
