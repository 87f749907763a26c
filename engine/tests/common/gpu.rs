//! Shared by the engine's GPU tests (included by path): one adapter per test binary, its
//! compilation targets with and without subgroup operations, and a layout compiled for it.
// Each test binary uses what it needs of these.
#![allow(dead_code)]

use lightgraph_engine::{Gpu, Graph, Program, Specialization, Target, compile};
use std::sync::OnceLock;

/// The adapter (lavapipe in CI).
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new(None).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"))
}

/// The adapter's target, and the same without subgroup operations when it has them.
pub fn targets() -> Vec<(&'static str, Target)> {
    let with = gpu().target();
    let mut out = vec![("adapter", with.clone())];
    if with.subgroups() {
        out.push(("no subgroups", with.without_subgroups()));
    }
    out
}

/// `layout` of `graph` compiled for the adapter with the graph's own constants.
pub fn program(graph: &Graph, layout: &str) -> Program {
    compile(
        graph,
        layout,
        &graph.layouts[layout],
        &Specialization::default(),
        &gpu().target(),
    )
    .unwrap()
}
