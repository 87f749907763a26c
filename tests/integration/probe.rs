//! Runs WGSL library functions on the GPU for tests. A probe is a one-pass graph, written to
//! a temporary folder: the pass `probe` (`Start(over: "N")`, item `ProbeItem { index: u32 }`)
//! is WGSL the test supplies, compiled with the library files and the resources of
//! `graphs/pt.ron` (read from that graph, so whatever resources it gains are declared here
//! too), fed the scene's data, and writes `vec4<f32>` results into `out`.
//!
//! The WGSL defines `fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool`, writes
//! `out[index * PER_INDEX + k]` for `k < PER_INDEX`, and returns `false`. It may read
//! `probe_in: array<vec4<f32>>`, the `input` the test passes, and seed random numbers with
//! `rng_seed(frame.seed, frame.index, index)`.

use crate::common::gpu;
use lightgraph::run::{LoadedScene, device_flags, kernel_flags, load_graph};
use lightgraph_engine::graph::Resource;
use lightgraph_engine::ir::Scope;
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, Vfs, compile};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::BvhKind;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};

/// A scene for probing, from RON text (no glTF asset).
pub fn scene(text: &str) -> LoadedScene {
    LoadedScene::parse("probe-scene.ron", text, BvhKind::Bvh2, None).expect("the probe scene parses")
}

/// The graph file of a probe: `pt`'s library, counters and resources, plus `probe_in`,
/// `out` and the pass, whose reads are derived from its WGSL (a scene resource it does not
/// use, or uses only under a flag that is off, is neither bound nor asked for).
fn graph_text(pt: &Graph) -> String {
    let mut s = String::from("(\n    name: \"probe\",\n    library: [\n");
    for file in &pt.library {
        let _ = writeln!(s, "        {file:?},");
    }
    s.push_str("    ],\n    passes: [Pass(name: \"probe\", item: \"ProbeItem\", source: \"probe/probe.wgsl\", role: Start(over: \"N\"), writes: [\"out\"])],\n    resources: {\n");
    for Resource { name, decl: r } in &pt.resources {
        let scope = match r.scope {
            Scope::External => "External",
            Scope::Persistent => "Persistent",
            Scope::Transient => "Transient",
        };
        let count = r.count.as_ref().map(|c| format!("count: {c:?}, ")).unwrap_or_default();
        let _ = writeln!(s, "        {name:?}: (ty: {:?}, {count}scope: {scope}),", r.ty);
    }
    s.push_str("        \"probe_in\": (ty: \"array<vec4<f32>>\", scope: External),\n");
    s.push_str("        \"out\": (ty: \"vec4<f32>\", count: \"N * PER_INDEX\", scope: Persistent),\n    },\n");
    s.push_str("    counters: [");
    for c in &pt.counters {
        let _ = write!(s, "{c:?}, ");
    }
    s.push_str("],\n    outputs: [\"out\"],\n    layouts: { \"fused\": (kernels: [[\"probe\"]]) },\n    default_layout: \"fused\",\n)\n");
    s
}

/// Runs `wgsl`'s `probe` for every index below `n` with `per_index` results each, on the
/// data of `scene`, with `input` readable as `probe_in` and extra `constants`; returns `out`.
pub fn probe(
    scene: &LoadedScene,
    wgsl: &str,
    n: u32,
    per_index: u32,
    input: &[[f32; 4]],
    constants: &[(&str, ConstValue)],
) -> Vec<[f32; 4]> {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let dir = std::env::temp_dir().join(format!(
        "lightgraph-probe-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(dir.join("probe")).unwrap();
    let pt = load_graph("pt").unwrap();
    std::fs::write(dir.join("probe.ron"), graph_text(&pt)).unwrap();
    std::fs::write(
        dir.join("probe/probe.wgsl"),
        format!("struct ProbeItem {{ index: u32 }}\n{wgsl}"),
    )
    .unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let vfs = Vfs::new(vec![Layer::Dir(dir.clone()), Layer::Dir(root)]);
    let result = run(&vfs, &pt, scene, n, per_index, input, constants);
    std::fs::remove_dir_all(&dir).unwrap();
    result
}

fn run(
    vfs: &Vfs,
    pt: &Graph,
    scene: &LoadedScene,
    n: u32,
    per_index: u32,
    input: &[[f32; 4]],
    constants: &[(&str, ConstValue)],
) -> Vec<[f32; 4]> {
    let graph = Graph::load(vfs, "probe.ron").unwrap_or_else(|e| panic!("{e}"));
    let mut values: BTreeMap<String, ConstValue> = pt.constants.clone();
    for name in ["WIDTH", "HEIGHT", "PIXELS", "SAMPLES_PER_PIXEL", "PATHS"] {
        values.insert(name.to_string(), ConstValue::U32(1));
    }
    values.insert("N".to_string(), ConstValue::U32(n));
    values.insert("PER_INDEX".to_string(), ConstValue::U32(per_index));
    values.extend(constants.iter().map(|(k, v)| (k.to_string(), *v)));
    let flags = kernel_flags(device_flags(gpu()), scene, false);
    let spec = Specialization {
        constants: values,
        flags,
    };
    let program =
        compile(&graph, "fused", &graph.layouts["fused"], &spec, &gpu().target()).unwrap_or_else(|e| panic!("{e}"));
    let camera = CompiledScene::camera(&scene.scene, 1, 1);
    let mut externals = scene.compiled.resources(&camera);
    externals.retain(|name, _| graph.resource(name).is_some_and(|r| r.decl.scope == Scope::External));
    let input: &[[f32; 4]] = if input.is_empty() { &[[0.0; 4]] } else { input };
    externals.insert("probe_in".to_string(), bytemuck::cast_slice(input).to_vec());
    let mut instance = Instance::new(gpu(), program, &externals).unwrap();
    instance.run_frame(0, 1).unwrap();
    bytemuck::pod_collect_to_vec(&instance.read("out").unwrap())
}

#[test]
fn probe_reads_input_and_scene_data() {
    let s = scene(
        r#"Scene(
            camera: (position: (0, -4, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 40.0),
            materials: {"a": (diffuse: (0.25, 0.5, 0.75)), "b": (pbr: (base_color: (0.1, 0.2, 0.3), roughness: 0.5))},
            shapes: [Sphere(center: (0, 0, 0), radius: 1.0, material: "a")],
            lights: [Background(radiance: (1, 1, 1))],
        )"#,
    );
    let wgsl = "fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
        out[index * PER_INDEX] = probe_in[index] * SCALE;
        out[index * PER_INDEX + 1u] = vec4<f32>(materials[index].diffuse, f32(scene.num_materials));
        return false;
    }";
    let input = [[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]];
    let out = probe(&s, wgsl, 2, 2, &input, &[("SCALE", ConstValue::F32(0.5))]);
    assert_eq!(out.len(), 4);
    assert_eq!(out[0], [0.5, 1.0, 1.5, 2.0]);
    assert_eq!(out[2], [2.5, 3.0, 3.5, 4.0]);
    assert_eq!(out[1], [0.25, 0.5, 0.75, 2.0]);
    assert_eq!(out[3], [0.1, 0.2, 0.3, 2.0]);
}
