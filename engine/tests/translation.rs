//! A kernel that naga validates but panics translating for the driver is an error naming the
//! layout and the kernel, not a crash. naga 30's SPIR-V writer panics ("Expression [4] is not
//! cached!") on a pointer to a field reached through a pointer parameter passed on to another
//! function; when a naga release fixes that, this test fails and the hint in
//! engine/src/runtime/pipelines.rs goes with it.

use lightgraph_engine::{Graph, Instance, Layer, Vfs};
use std::collections::BTreeMap;

#[path = "common/gpu.rs"]
mod gpu_common;
use gpu_common::{gpu, program};

/// Valid WGSL that naga 30's SPIR-V writer cannot translate: `step` passes `&(*w).inner` on.
const WGSL: &str = "struct Inner { t: f32, n: u32 }
struct Walk { a: vec3<f32>, inner: Inner, k: u32 }
struct Item { index: u32 }

fn touch(x: f32, inner: ptr<function, Inner>) { (*inner).t = x; (*inner).n += 1u; }

fn step(w: ptr<function, Walk>) -> bool {
    touch((*w).a.x, &(*w).inner);
    (*w).k += 1u;
    return (*w).k < 3u;
}

fn make(it: ptr<function, Item>, index: u32) -> bool {
    var w: Walk;
    w.a = vec3<f32>(f32(index));
    while (step(&w)) {}
    out[index] = w.inner.n;
    return false;
}
";

const RON: &str = r#"(
    name: "p",
    passes: [ Pass(name: "make", item: "Item", source: "p.wgsl", role: Start(over: "64"), writes: ["out"]) ],
    resources: { "out": (ty: "u32", count: "64") },
    outputs: ["out"],
    layouts: { "fused": (kernels: [["make"]]) },
    default_layout: "fused",
)"#;

#[test]
fn a_kernel_naga_cannot_translate_is_an_error_naming_it() {
    let dir = std::env::temp_dir().join(format!("lg-naga-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("p.ron"), RON).unwrap();
    std::fs::write(dir.join("p.wgsl"), WGSL).unwrap();
    let g = Graph::load(&Vfs::new(vec![Layer::Dir(dir)]), "p.ron").unwrap();
    let error = match Instance::new(gpu(), program(&g, "fused"), &BTreeMap::new()) {
        Ok(_) => panic!("naga translated the kernel: its bug is fixed, so drop the hint and this test"),
        Err(e) => e.to_string(),
    };
    assert!(
        error.contains("layout 'fused', kernel 'k0_make': naga panicked") && error.contains("f(&(*p).field)"),
        "{error}"
    );
}
