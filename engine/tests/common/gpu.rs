//! Shared by the engine's GPU tests (included by path): one adapter per test binary, and its
//! compilation targets with and without subgroup operations.

use lightgraph_engine::{Gpu, Target};
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
