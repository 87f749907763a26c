//! The engine on a graph with no light transport: every legal layout of the Collatz graph
//! must produce exactly the numbers the CPU computes, and illegal layouts must be refused
//! with messages that name the passes and resources involved.

use lightgraph_engine::ir::{LayoutDecl, LoopMode, Policy};
use lightgraph_engine::program::RuntimeChecks;
use lightgraph_engine::{ConstValue, Gpu, Graph, Instance, Layer, Plan, Specialization, Vfs, compile};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::OnceLock;

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new(None).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"))
}

fn graph() -> Graph {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    Graph::load(&Vfs::new(vec![Layer::Dir(dir)]), "collatz.ron").expect("the test graph loads")
}

fn cpu_steps(n: u32) -> Vec<u32> {
    (1..=n as u64)
        .map(|mut v| {
            let mut s = 0;
            while v != 1 {
                v = if v % 2 == 0 { v / 2 } else { 3 * v + 1 };
                s += 1;
            }
            s
        })
        .collect()
}

type Outputs = (Vec<u32>, Vec<u32>, BTreeMap<String, u64>);

fn run(layout: &str, n: u32) -> Outputs {
    let g = graph();
    let decl = g.layouts[layout].clone();
    run_decl(&g, layout, decl, n)
}

/// Runs one frame of layout `decl` (named `name`) over the numbers 1..=n: the steps of each
/// walk, the histogram and the counters.
fn run_decl(g: &Graph, name: &str, decl: LayoutDecl, n: u32) -> Outputs {
    let spec = Specialization {
        constants: [("N".to_string(), ConstValue::U32(n))].into_iter().collect(),
        ..Default::default()
    };
    let program = compile(g, name, &decl, &spec, &gpu().target()).unwrap();
    let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    let stats = instance.run_frame(0, 0).unwrap();
    let steps = bytemuck::pod_collect_to_vec(&instance.read("steps").unwrap());
    let summary = bytemuck::pod_collect_to_vec(&instance.read("summary").unwrap());
    (steps, summary, stats.counters)
}

#[test]
fn every_legal_layout_computes_the_same_walks() {
    let n = 1000;
    let expected = cpu_steps(n);
    let mut histogram = vec![0u32; 64];
    for &s in &expected {
        histogram[(s as usize).min(63)] += 1;
    }
    let iterations: u64 = expected.iter().map(|&s| s as u64 + 1).sum();
    for layout in [
        "fused",
        "split",
        "split_aos",
        "split_chunked",
        "loop_with_consumer",
        "loop_in_kernel_after_start",
    ] {
        let (steps, summary, counters) = run(layout, n);
        assert_eq!(steps, expected, "layout {layout}: steps");
        assert_eq!(summary, histogram, "layout {layout}: histogram");
        assert_eq!(counters["iterations"], iterations, "layout {layout}: iteration counter");
        assert_eq!(counters["walks"], n as u64, "layout {layout}: walk counter");
    }
}

#[test]
fn every_enumerated_layout_computes_the_same_walks() {
    let g = graph();
    let layouts = lightgraph_engine::auto::legal_layouts(&g, &Default::default());
    // seed/step/record in phase 0 (5 partitions) by loop mode and policy, minus the illegal
    // and the duplicates; the named layouts of the file are among them.
    assert!(
        layouts.len() >= 8,
        "{:?}",
        layouts.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    let n = 300;
    let expected = cpu_steps(n);
    for (name, decl) in layouts {
        eprintln!("layout {name}");
        let decl = LayoutDecl {
            threads: Some(37),
            ..decl
        };
        let (steps, _, counters) = run_decl(&g, &name, decl, n);
        assert_eq!(steps, expected, "layout {name}");
        assert_eq!(counters["walks"], n as u64, "layout {name}");
    }
}

#[test]
fn passes_nobody_reads_are_culled() {
    let g = graph();
    assert_eq!(
        g.culled.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        vec!["unused"]
    );
    assert_eq!(g.phases.len(), 2, "the culled pass's phase is gone");
}

#[test]
fn chunked_layouts_run_in_several_chunks() {
    let g = graph();
    let decl = &g.layouts["split_chunked"];
    let program = compile(&g, "split_chunked", decl, &Specialization::default(), &gpu().target()).unwrap();
    assert_eq!(program.resolved.domains[0].chunk, 100);
    assert_eq!(program.resolved.domains[0].default, 1000);
    assert_eq!(
        program.resolved.state_capacity.values().copied().collect::<Vec<_>>(),
        vec![100]
    );
}

fn plan_error(layout: &str) -> String {
    Plan::new(&graph(), layout)
        .expect_err("the layout is refused")
        .to_string()
}

#[test]
fn illegal_layouts_are_refused_with_names() {
    let e = plan_error("queue_in_kernel_loop");
    assert!(
        e.contains("'step'") && e.contains("'done'") && e.contains("'record'"),
        "{e}"
    );
    let e = plan_error("across_barrier");
    assert!(
        e.contains("'summarize'") && e.contains("'histogram'") && e.contains("barrier"),
        "{e}"
    );
    assert!(
        e.starts_with("collatz.ron:"),
        "the error is located in the graph file: {e}"
    );
    let e = plan_error("two_entries");
    assert!(e.contains("two kernels") && e.contains("'record'"), "{e}");
    let e = plan_error("missing_pass");
    assert!(e.contains("'summarize'") && e.contains("no kernel"), "{e}");
    let e = plan_error("NoSuchLayout");
    assert!(
        e.contains("unknown layout 'NoSuchLayout'") && e.contains("split_aos"),
        "{e}"
    );
}

/// The Collatz graph with the stream's `per_call` written as `per_call`.
fn graph_with_per_call(per_call: &str) -> Graph {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let text = std::fs::read_to_string(dir.join("collatz.ron"))
        .unwrap()
        .replace("per_call: 1)", &format!("per_call: {per_call})"));
    Graph::from_text(&Vfs::new(vec![Layer::Dir(dir)]), "collatz.ron", &text).expect("the graph loads")
}

#[test]
fn per_call_expressions_size_queues_from_constants() {
    let compile = |per_call: &str, bins: u32| {
        let g = graph_with_per_call(per_call);
        let spec = Specialization {
            constants: [("BINS".to_string(), ConstValue::U32(bins))].into_iter().collect(),
            ..Default::default()
        };
        compile(&g, "split_chunked", &g.layouts["split_chunked"], &spec, &gpu().target())
    };
    // 100 items per chunk, each emitting at most per_call walks into the queue.
    let number = compile("1", 64).unwrap();
    assert_eq!(
        number.resolved.queue_capacity[&number.plan.graph.stream_id("done").unwrap()],
        100
    );
    let expr = compile("\"BINS / 32 + 1\"", 64).unwrap();
    assert_eq!(
        expr.resolved.queue_capacity[&expr.plan.graph.stream_id("done").unwrap()],
        300
    );
    let e = compile("\"BINS - 64\"", 64)
        .expect_err("per_call 0 is refused")
        .to_string();
    assert!(e.contains("stream 'done': per_call BINS - 64 is 0"), "{e}");
    let e = compile("\"BINS - UNKNOWN\"", 64)
        .expect_err("unknown constant")
        .to_string();
    assert!(e.contains("per_call: unknown constant 'UNKNOWN'"), "{e}");
    let e = Graph::from_text(
        &Vfs::new(vec![Layer::Dir(
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data"),
        )]),
        "collatz.ron",
        &std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/collatz.ron"))
            .unwrap()
            .replace("per_call: 1)", "per_call: \"BINS +\")"),
    )
    .expect_err("a malformed per_call is refused")
    .to_string();
    assert!(e.contains("stream 'done': per_call:"), "{e}");
}

/// `regenerate_at` holds idle slots back until enough of the pool is idle: every host-loop
/// regeneration layout still walks every number exactly once, with a pool of 37 slots (so
/// refills come in waves), and the field is refused where there is no such pool.
#[test]
fn regeneration_behind_a_gate_walks_every_number_once() {
    let g = graph();
    let n = 300;
    let expected = cpu_steps(n);
    let mut gated = 0;
    for (name, decl) in lightgraph_engine::auto::legal_layouts(&g, &Default::default()) {
        if decl.policy != Policy::Regeneration || decl.loops != LoopMode::Host {
            let e = Plan::with_decl(
                &g,
                &name,
                LayoutDecl {
                    regenerate_at: Some(0.6),
                    ..decl
                },
            )
            .expect_err("regenerate_at without a host-loop regeneration pool is refused")
            .to_string();
            assert!(e.contains("regenerate_at needs policy: Regeneration"), "{e}");
            continue;
        }
        for at in [0.6, 1.0] {
            let decl = LayoutDecl {
                threads: Some(37),
                regenerate_at: Some(at),
                ..decl.clone()
            };
            let (steps, _, counters) = run_decl(&g, &name, decl, n);
            assert_eq!(steps, expected, "layout {name}, regenerate_at {at}");
            assert_eq!(counters["walks"], n as u64, "layout {name}, regenerate_at {at}");
        }
        gated += 1;
    }
    assert!(gated > 0, "no host-loop regeneration layout to gate");
    let fused = Plan::new(&g, "fused").unwrap().layout;
    let e = Plan::with_decl(
        &g,
        "fused",
        LayoutDecl {
            regenerate_at: Some(1.5),
            ..fused
        },
    )
    .expect_err("a fraction above 1 is refused")
    .to_string();
    assert!(e.contains("regenerate_at 1.5 is not in (0, 1]"), "{e}");
}

/// The Collatz graph with `loop_bounds: {"<item>": "<bound>"}` and a constant `BOUND`.
fn graph_with_loop_bound(item: &str, bound: &str) -> Result<Graph, String> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let text = std::fs::read_to_string(dir.join("collatz.ron"))
        .unwrap()
        .replace("\"BINS\": U32(64) }", "\"BINS\": U32(64), \"BOUND\": U32(1) }")
        .replace(
            "    layouts: {",
            &format!("    loop_bounds: {{\"{item}\": \"{bound}\"}},\n    layouts: {{"),
        );
    Graph::from_text(&Vfs::new(vec![Layer::Dir(dir)]), "collatz.ron", &text).map_err(|e| e.to_string())
}

/// One frame over 1..=n with the constant BOUND: the walks' steps and the host-loop
/// iterations, or the frame's error.
fn run_bounded(g: &Graph, name: &str, decl: LayoutDecl, n: u32, bound: u32) -> Result<(Vec<u32>, u32), String> {
    let mut instance = bounded_instance(g, name, decl, n, bound);
    let stats = instance.run_frame(0, 0).map_err(|e| e.to_string())?;
    let steps = bytemuck::pod_collect_to_vec(&instance.read("steps").unwrap());
    Ok((steps, stats.host_iterations))
}

/// The instance of layout `decl` (named `name`) over 1..=n with the constant BOUND.
fn bounded_instance(g: &Graph, name: &str, decl: LayoutDecl, n: u32, bound: u32) -> Instance<'static> {
    let spec = Specialization {
        constants: [
            ("N".to_string(), ConstValue::U32(n)),
            ("BOUND".to_string(), ConstValue::U32(bound)),
        ]
        .into_iter()
        .collect(),
        ..Default::default()
    };
    let program = compile(g, name, &decl, &spec, &gpu().target()).unwrap();
    Instance::new(gpu(), program, &BTreeMap::new()).unwrap()
}

/// 300 walks, their steps on the CPU, the loop iterations they need (the loop pass runs once
/// more than a walk's steps: the last call finds 1) and the graph with a loop bound.
fn bounded_walks() -> (u32, Vec<u32>, u32, Graph) {
    let n = 300;
    let expected = cpu_steps(n);
    let needed = expected.iter().max().unwrap() + 1;
    (n, expected, needed, graph_with_loop_bound("Walk", "BOUND").unwrap())
}

/// With a loop bound, a host loop whose items all start at once runs exactly the bound's
/// iterations (no read-back between them) and computes the same walks; one iteration too few
/// is an error naming the bound; a pool smaller than the chunk falls back to read-backs.
#[test]
fn bounded_host_loops_run_their_bound_and_catch_a_short_one() {
    let (n, expected, needed, g) = bounded_walks();
    let mut host = 0;
    for (name, decl) in lightgraph_engine::auto::legal_layouts(&g, &Default::default()) {
        if decl.loops != LoopMode::Host {
            continue;
        }
        host += 1;
        let (steps, iterations) = run_bounded(&g, &name, decl.clone(), n, needed).unwrap();
        assert_eq!(steps, expected, "layout {name}");
        assert!(
            iterations > 0 && iterations % needed == 0,
            "layout {name}: {iterations} host iterations, not whole runs of the bound {needed}"
        );
        let e = run_bounded(&g, &name, decl.clone(), n, needed - 1).expect_err("a bound one short is caught");
        assert!(
            e.contains(&format!(
                "still alive after {} loop iterations, the graph's loop_bounds for 'Walk'",
                needed - 1
            )),
            "layout {name}: {e}"
        );
        if decl.policy != Policy::Naive {
            // 37 threads for 300 walks: items start over many iterations, so the host reads
            // back as before, and the short bound does not apply.
            let small = LayoutDecl {
                threads: Some(37),
                ..decl
            };
            let (steps, _) = run_bounded(&g, &name, small, n, needed - 1).unwrap();
            assert_eq!(steps, expected, "layout {name} with 37 threads");
        }
    }
    assert!(host > 2, "too few host-loop layouts: {host}");
    let e = graph_with_loop_bound("Nope", "BOUND").expect_err("an unknown item is refused");
    assert!(e.contains("loop_bounds: no pass runs over items of type 'Nope'"), "{e}");
    let e = graph_with_loop_bound("Walk", "BOUND +").expect_err("a malformed bound is refused");
    assert!(e.contains("loop_bounds of 'Walk':"), "{e}");
}

/// Two batches in flight at once: each is collected in order with its own counters and
/// loop iterations, a third is refused until one is collected, and an error of a batch
/// (here a loop bound one short) surfaces when that batch is collected.
#[test]
fn batches_in_flight_are_collected_in_order_with_their_own_statistics() {
    let (n, expected, needed, g) = bounded_walks();
    let split = || g.layouts["split"].clone();
    let mut instance = bounded_instance(&g, "split", split(), n, needed);
    let single = instance.run_frame(0, 0).unwrap();
    instance.submit_frames(1, 1, 0).unwrap();
    instance.submit_frames(2, 2, 0).unwrap();
    assert_eq!(instance.frames_in_flight(), 2);
    let e = instance.submit_frames(4, 1, 0).unwrap_err().to_string();
    assert!(e.contains("2 batches are in flight already"), "{e}");
    let first = instance.collect_frames().unwrap().expect("the first batch");
    let second = instance.collect_frames().unwrap().expect("the second batch");
    assert!(instance.collect_frames().unwrap().is_none());
    assert!(!single.counters.is_empty());
    assert_eq!(first.counters, single.counters, "one frame");
    for (name, &v) in &single.counters {
        assert_eq!(second.counters[name], 2 * v, "counter {name} over two frames");
    }
    assert_eq!((first.host_iterations, second.host_iterations), (needed, 2 * needed));
    let steps: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("steps").unwrap());
    assert_eq!(steps, expected);

    let mut short = bounded_instance(&g, "split", split(), n, needed - 1);
    short.submit_frames(0, 1, 0).unwrap();
    short.submit_frames(1, 1, 0).unwrap();
    let e = short.collect_frames().unwrap_err().to_string();
    assert!(e.contains("still alive after"), "{e}");
}

/// The text of function `name` in `wgsl`, from its `fn` line to its closing brace.
fn function_text<'a>(wgsl: &'a str, name: &str) -> &'a str {
    let start = wgsl
        .find(&format!("fn {name}("))
        .unwrap_or_else(|| panic!("no function {name}"));
    let end = start + wgsl[start..].find("\n}\n").expect("a closing brace");
    &wgsl[start..end]
}

/// `step` reads every word of `Walk` (index, value, steps) but writes only `value` and
/// `steps`: in the split layout its kernel loads three words and stores two, and the
/// layout still computes the CPU's walks (`every_legal_layout_computes_the_same_walks`).
#[test]
fn a_state_kernel_stores_only_the_words_its_passes_write() {
    let g = graph();
    let spec = Specialization {
        constants: [("N".to_string(), ConstValue::U32(10))].into_iter().collect(),
        ..Default::default()
    };
    let program = compile(
        &g,
        "split",
        &g.layouts["split"],
        &spec,
        &lightgraph_engine::Target::default(),
    )
    .unwrap();
    let plan = &program.plan;
    let k = plan
        .kernel_ids()
        .find(|&k| plan.kernels[k].name.contains("step"))
        .unwrap();
    let traffic = lightgraph_engine::codegen::slot_traffic(&program.plan, &program.resolved, k).unwrap();
    assert_eq!(
        (traffic.load, traffic.store, traffic.words),
        (vec![0, 1, 2], vec![1, 2], 3)
    );
    let text = program.kernels[k.0].source.text();
    let store = function_text(text, "lg_store_state_0_part");
    let stored: Vec<&str> = store.lines().filter(|l| l.contains("lg_state_0[")).collect();
    assert_eq!(stored.len(), 2, "{store}");
    assert!(stored.iter().all(|l| !l.contains("v.index")), "{store}");
    let load = function_text(text, "lg_load_state_0_part");
    assert_eq!(load.lines().filter(|l| l.contains("lg_state_0[")).count(), 3, "{load}");
    assert!(
        !text.contains("fn lg_store_state_0("),
        "the whole-item store is left out"
    );
}

/// A layout's constants compile into its program unless the program is given them (VCMsk's
/// culling by one is tested with VCM); a layout naming no constant of the graph, or one of
/// another type, is refused at load with the layout and the constant named.
#[test]
fn a_layout_compiles_with_its_constants_unless_given_them() {
    let g = graph();
    let mut decl = g.layouts["fused"].clone();
    decl.constants.insert("BINS".to_string(), ConstValue::U32(32));
    let compiled = |given: &[(&str, ConstValue)]| {
        let spec = Specialization {
            constants: given.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            ..Default::default()
        };
        compile(&g, "fused", &decl, &spec, &gpu().target())
            .unwrap()
            .plan
            .graph
            .constants["BINS"]
    };
    assert_eq!(compiled(&[]), ConstValue::U32(32));
    assert_eq!(compiled(&[("BINS", ConstValue::U32(16))]), ConstValue::U32(16));
    let text =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/collatz.ron")).unwrap();
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let vfs = Vfs::new(vec![Layer::Dir(dir)]);
    for (set, message) in [
        (
            r#""BINZ": U32(8)"#,
            "layout 'fused': sets 'BINZ', which is no constant of the graph",
        ),
        (
            r#""BINS": F32(8.0)"#,
            "layout 'fused': constant 'BINS' is u32 in the graph but set as f32",
        ),
    ] {
        let bad = text.replace(
            r#""fused": (kernels: [["seed", "step", "record"], ["summarize"]]),"#,
            &format!(r#""fused": (kernels: [["seed", "step", "record"], ["summarize"]], constants: {{ {set} }}),"#),
        );
        let e = Graph::from_text(&vfs, "bad.ron", &bad).unwrap_err().to_string();
        assert!(e.starts_with("bad.ron:") && e.contains(message), "{e}");
    }
}

/// A layout with `loop_guards: false` compiles its pass kernels without wgpu's loop guards (the
/// engine's own kernels never have them) and computes the walks the guarded layout computes.
#[test]
fn a_layout_may_leave_the_loop_guards_out() {
    let g = graph();
    for layout in ["fused", "split"] {
        let mut decl = g.layouts[layout].clone();
        assert!(decl.loop_guards, "the guards are on by default");
        decl.loop_guards = false;
        let program = compile(&g, layout, &decl, &Specialization::default(), &gpu().target()).unwrap();
        assert!(
            program.kernels.iter().all(|k| k.checks == RuntimeChecks::NoLoopGuards),
            "{layout}"
        );
        assert_eq!(run_decl(&g, layout, decl, 1000), run(layout, 1000), "{layout}");
    }
}

/// A pool whose items would fill a binding exactly is cut to what fits beside the buffer's
/// header, not refused (the boundary holds a header before its items).
#[test]
fn a_pool_is_cut_to_what_fits_one_binding_with_its_header() {
    let g = graph();
    let mut decl = g.layouts["split"].clone();
    decl.policy = Policy::Compaction;
    decl.threads = Some(256);
    let spec = Specialization {
        constants: [("N".to_string(), ConstValue::U32(700))].into_iter().collect(),
        ..Default::default()
    };
    let item_bytes = 4 * compile(&g, "pool", &decl, &spec, &gpu().target())
        .unwrap()
        .resolved
        .words["Walk"]
        .len() as u64;
    let target = lightgraph_engine::Target {
        max_binding_bytes: 256 * item_bytes,
        ..gpu().target()
    };
    let program = compile(&g, "pool", &decl, &spec, &target).unwrap();
    let fits = (256 * item_bytes - lightgraph_engine::resolve::BOUNDARY_HEADER) / item_bytes;
    assert_eq!(program.resolved.pools.values().copied().max(), Some(fits));
    let (steps, _, _) = run_decl(&g, "pool", decl, 700);
    assert_eq!(steps, cpu_steps(700));
}
