//! Reads and writes derived from the WGSL: a pass that leaves out `reads` or `writes` gets the
//! resources its function uses, with the specialisation's flags, before culling and planning
//! use them; listed ones are still checked; a resource used only under a flag that is off is
//! not bound; a catalog's resources join only where a derived pass uses them.

use lightgraph_engine::explain::report;
use lightgraph_engine::{ConstValue, Graph, Layer, Specialization, Target, Vfs, compile};
use std::collections::{BTreeMap, BTreeSet};

const WGSL: &str = "struct Item { index: u32, value: u32 }

fn make(it: ptr<function, Item>, index: u32) -> bool {
    var value = source[index];
#if EXTRA
    value += extra[0];
#endif
    *it = Item(index, value);
    return true;
}

fn store(it: ptr<function, Item>) -> bool {
    out[(*it).index] = (*it).value;
#if TALLY
    atomicAdd(&tally, 1u);
#endif
    return false;
}
";

/// The test graph with `make` and `store` given `make_lists` and `store_lists` (RON fields,
/// each ending in a comma, or empty), its outputs `outputs`.
fn graph_text(make_lists: &str, store_lists: &str, outputs: &str) -> String {
    format!(
        r#"(
    name: "derive",
    passes: [
        Pass(name: "make", item: "Item", source: "derive.wgsl", role: Start(over: "N"), {make_lists}),
        Pass(name: "store", item: "Item", source: "derive.wgsl", role: Step, {store_lists}),
    ],
    resources: {{
        "source": (ty: "u32", count: "N"),
        "extra": (ty: "u32", count: "1"),
        "out": (ty: "u32", count: "N"),
        "spare": (ty: "u32", count: "N"),
        "tally": (ty: "atomic<u32>"),
    }},
    constants: {{ "N": U32(64) }},
    outputs: [{outputs}],
    layouts: {{ "fused": (kernels: [["make", "store"]]) }},
    default_layout: "fused",
)"#
    )
}

/// A folder of its own holding `files`.
fn folder(name: &str, files: &[(&str, &str)]) -> Vfs {
    let dir = std::env::temp_dir().join(format!("lightgraph-derived-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    Vfs::new(vec![Layer::Dir(dir)])
}

fn load(name: &str, graph: &str) -> lightgraph_engine::Result<Graph> {
    Graph::load(
        &folder(name, &[("derive.ron", graph), ("derive.wgsl", WGSL)]),
        "derive.ron",
    )
}

fn flags(names: &[&str]) -> BTreeSet<String> {
    names.iter().map(|s| s.to_string()).collect()
}

fn lists(g: &Graph, pass: &str) -> (Vec<String>, Vec<String>) {
    let p = &g.passes[g.pass_index(pass).unwrap().0];
    (p.decl.reads.clone(), p.decl.writes.clone())
}

fn strings(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

#[test]
fn passes_that_leave_out_their_lists_get_them_from_the_wgsl() {
    let graph = load("omitted", &graph_text("", "", "\"out\"")).unwrap();
    // Derived before culling: `store` writes the output, so nothing is culled.
    assert!(graph.culled.is_empty(), "{:?}", graph.culled);
    let off = graph.specialize_for(&BTreeMap::new(), &flags(&[])).unwrap();
    assert_eq!(lists(&off, "make"), (strings(&["source"]), vec![]));
    assert_eq!(lists(&off, "store"), (vec![], strings(&["out"])));
    let on = graph.specialize_for(&BTreeMap::new(), &flags(&["EXTRA"])).unwrap();
    assert_eq!(lists(&on, "make"), (strings(&["extra", "source"]), vec![]));
    // A true Bool constant is a flag too.
    let by_constant = graph
        .specialize_for(&[("EXTRA".to_string(), ConstValue::Bool(true))].into(), &flags(&[]))
        .unwrap();
    assert_eq!(lists(&by_constant, "make"), (strings(&["extra", "source"]), vec![]));
}

#[test]
fn a_resource_used_only_under_a_flag_that_is_off_is_not_bound() {
    let graph = load("bound", &graph_text("", "", "\"out\"")).unwrap();
    let decl = graph.layout("fused").unwrap().clone();
    let bound = |names: &[&str]| {
        let spec = Specialization {
            constants: BTreeMap::new(),
            flags: flags(names),
        };
        let program = compile(&graph, "fused", &decl, &spec, &Target::default()).unwrap();
        let extra = program.plan.graph.resource_id("extra");
        let used = extra.is_some_and(|r| program.resolved.used.contains(&r));
        let binds = program.kernels.iter().any(|k| {
            k.uses
                .iter()
                .any(|u| extra.is_some_and(|r| u.buffer == lightgraph_engine::resolve::BufferRef::Resource(r)))
        });
        (used, binds, report(&program, &|_| None))
    };
    let (used, binds, text) = bound(&[]);
    assert!(!used && !binds, "'extra' is used only under EXTRA");
    assert!(
        text.contains("derived from the WGSL") && text.contains("  make: reads source; writes nothing"),
        "{text}"
    );
    assert!(text.contains("  store: reads nothing; writes out"), "{text}");
    let (used, binds, _) = bound(&["EXTRA"]);
    assert!(used && binds, "with EXTRA, 'extra' is read and bound");
}

#[test]
fn listed_lists_are_still_checked() {
    let target = Target::default();
    let compiled = |name: &str, make: &str, store: &str, with: &[&str]| {
        let graph = load(name, &graph_text(make, store, "\"out\"")).unwrap();
        let decl = graph.layout("fused").unwrap().clone();
        let spec = Specialization {
            constants: BTreeMap::new(),
            flags: flags(with),
        };
        compile(&graph, "fused", &decl, &spec, &target).map(|_| ())
    };
    // `store` lists the write it makes without TALLY, not the one it makes with it; its
    // reads are derived.
    compiled("writes", "", "writes: [\"out\"],", &[]).unwrap();
    let e = compiled("tally", "", "writes: [\"out\"],", &["TALLY"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pass 'store' writes resource 'tally' but does not declare it in `writes`"),
        "{e}"
    );
    // `make` lists reads without the one it makes; its writes are derived.
    let e = compiled("reads", "reads: [\"spare\"],", "", &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pass 'make' reads resource 'source' but does not declare it in `reads`"),
        "{e}"
    );
    // Listed right, derived where left out: fine.
    compiled("right", "reads: [\"source\"],", "writes: [\"out\"],", &[]).unwrap();
}

#[test]
fn a_catalog_resource_joins_where_a_derived_pass_uses_it() {
    let catalog = r#"(
    resources: {
        "source": (ty: "u32", count: "N"),
        "extra": (ty: "u32", count: "1"),
        "spare": (ty: "u32", count: "N"),
    },
    passes: [(name: "make", item: "Item", source: "derive.wgsl", role: Start(over: "N"))],
)"#;
    let graph = |entry: &str| {
        format!(
            r#"(
    name: "catalog",
    catalogs: ["cat.ron"],
    passes: [{entry}, Pass(name: "store", item: "Item", source: "derive.wgsl", role: Step)],
    resources: {{ "out": (ty: "u32", count: "N") }},
    constants: {{ "N": U32(64) }},
    outputs: ["out"],
    layouts: {{ "fused": (kernels: [["make", "store"]]) }},
    default_layout: "fused",
)"#
        )
    };
    let vfs = |name: &str, text: &str| folder(name, &[("g.ron", text), ("cat.ron", catalog), ("derive.wgsl", WGSL)]);
    let g = Graph::load(&vfs("catalog", &graph("Use(\"make\")")), "g.ron").unwrap();
    let names = |g: &Graph| g.resources.iter().map(|r| r.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&g), strings(&["out", "source"]));
    let with_extra = g.specialize_for(&BTreeMap::new(), &flags(&["EXTRA"])).unwrap();
    assert_eq!(names(&with_extra), strings(&["extra", "out", "source"]));
    let e = Graph::load(
        &vfs("usewith", &graph("UseWith(name: \"make\", reads: [\"spare\"])")),
        "g.ron",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("g.ron:") && e.contains("its catalog derives them from the WGSL"),
        "{e}"
    );
}

/// The test graph whose `make` stores the WGSL expression `value` (of `source` and `index`) and
/// whose `store` writes it out, loaded from a folder of its own.
fn with_value(name: &str, value: &str) -> Graph {
    let wgsl = format!(
        "struct Item {{ index: u32, value: u32 }}
fn make(it: ptr<function, Item>, index: u32) -> bool {{ *it = Item(index, {value}); return true; }}
fn store(it: ptr<function, Item>) -> bool {{ out[(*it).index] = (*it).value; return false; }}
"
    );
    let text = graph_text("", "", "\"out\"");
    Graph::load(
        &folder(name, &[("derive.ron", &text), ("derive.wgsl", &wgsl)]),
        "derive.ron",
    )
    .unwrap()
}

/// The error of specialising `graph` with no constants given and no flags.
fn default_view_error(graph: &Graph) -> String {
    graph
        .specialize_for(&BTreeMap::new(), &flags(&[]))
        .unwrap_err()
        .to_string()
}

#[test]
fn a_graph_whose_wgsl_needs_a_constant_only_the_program_gives_still_loads() {
    // `SCALE` is an f32 the host gives: the default constants' view cannot compile the WGSL
    // (a constant it does not know is taken for a u32), so it derives nothing and culls
    // nothing by it; a view that knows SCALE derives.
    let graph = with_value("later", "u32(f32(source[index]) * SCALE)");
    assert!(graph.culled.is_empty(), "{:?}", graph.culled);
    // Before any view derived (a derivation is kept per set of flags, whatever the values).
    let e = default_view_error(&graph);
    assert!(
        e.contains("derive.wgsl:2:"),
        "a view of every constant but SCALE reports the WGSL's error: {e}"
    );
    let scale = [("SCALE".to_string(), ConstValue::F32(0.5))].into();
    let live = graph.specialize_for(&scale, &flags(&[])).unwrap();
    assert_eq!(lists(&live, "make"), (strings(&["source"]), vec![]));
    assert_eq!(lists(&live, "store"), (vec![], strings(&["out"])));
}

#[test]
fn wgsl_naming_too_many_unknown_constants_is_an_error_not_a_panic() {
    // Each unknown upper-case name is taken for a host constant and declared as a u32, one a
    // compile; past the limit (64) the derivation stops with an error naming the graph.
    let names: Vec<String> = (0..70).map(|i| format!("K{i}")).collect();
    let graph = with_value("unknowns", &format!("source[index] + {}", names.join(" + ")));
    let e = default_view_error(&graph);
    assert!(
        e.contains("graph 'derive': its WGSL names more than 64 constants"),
        "{e}"
    );
}
