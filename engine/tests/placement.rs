//! Layouts need not list the passes the graph's default constants disable (another structure's
//! passes, chosen by a constant): set on, such a pass is placed by its chain, inside the kernel
//! of the pass before it or in a kernel of its own, as a layout listing it there would. A
//! layout may be `like` another, taking that one's fields where it gives none.

use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Graph, Layer, Plan, Vfs};
use std::collections::BTreeMap;

const WGSL: &str = "struct Item { value: u32 }
fn make(it: ptr<function, Item>, index: u32) -> bool { (*it).value = index; return true; }
fn a(it: ptr<function, Item>) -> bool { (*it).value += 1u; return true; }
fn b(it: ptr<function, Item>) -> bool { (*it).value += 2u; return true; }
fn finish(it: ptr<function, Item>) -> bool { out[(*it).value % N] = 1u; return false; }
fn side(it: ptr<function, Item>, index: u32) -> bool { out[index] += 1u; return false; }
";

/// The graph with the layouts `layouts` (RON map entries).
fn graph(layouts: &str) -> Graph {
    loaded(layouts).unwrap()
}

/// The graph with the layouts `layouts`, or the error loading it, with its text.
fn loaded(layouts: &str) -> lightgraph_engine::Result<Graph> {
    let text = format!(
        r#"(
    name: "modes",
    passes: [
        Pass(name: "make", item: "Item", source: "m.wgsl", role: Start(over: "N")),
        Pass(name: "a", item: "Item", source: "m.wgsl", role: Step, enabled: "MODE == 0"),
        Pass(name: "b", item: "Item", source: "m.wgsl", role: Step, enabled: "MODE == 1"),
        Pass(name: "finish", item: "Item", source: "m.wgsl", role: Step, writes: ["out"]),
        Pass(name: "side", item: "Item", source: "m.wgsl", role: Start(over: "N"), writes: ["out"], enabled: "MODE == 1"),
    ],
    resources: {{ "out": (ty: "u32", count: "N") }},
    constants: {{ "N": U32(16), "MODE": U32(0) }},
    outputs: ["out"],
    layouts: {{ {layouts} }},
    default_layout: "listed",
)"#
    );
    let dir = std::env::temp_dir().join(format!("lightgraph-placement-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("m.wgsl"), WGSL).unwrap();
    Graph::from_text(&Vfs::new(vec![Layer::Dir(dir)]), "modes.ron", &text)
}

/// The kernels of layout `name` with `MODE`: each one's name and passes.
fn kernels(g: &Graph, name: &str, mode: u32) -> Vec<(String, Vec<String>)> {
    let live = g
        .specialize(&BTreeMap::from([("MODE".to_string(), ConstValue::U32(mode))]))
        .unwrap();
    let decl: LayoutDecl = live.layout(name).unwrap().clone();
    let plan = Plan::with_decl(&live, name, decl).unwrap();
    plan.kernels
        .iter()
        .map(|k| {
            let chain = &live.chains[k.chain.0];
            let passes = chain.passes[k.segment.clone()]
                .iter()
                .map(|p| live.passes[p.0].decl.name.clone())
                .collect();
            (k.name.clone(), passes)
        })
        .collect()
}

#[test]
fn passes_a_default_constant_disables_are_placed_as_listed_ones() {
    let g = graph(
        r#""listed": (kernels: [["make", "a", "b", "finish"], ["side"]]),
           "short": (kernels: [["make", "a", "finish"]]),
           "split_listed": (kernels: [["make"], ["a", "b", "finish"], ["side"]], loops: Host),
           "split_short": (kernels: [["make"], ["a", "finish"]], loops: Host)"#,
    );
    for mode in [0, 1] {
        assert_eq!(kernels(&g, "short", mode), kernels(&g, "listed", mode), "MODE {mode}");
        assert_eq!(
            kernels(&g, "split_short", mode),
            kernels(&g, "split_listed", mode),
            "MODE {mode}"
        );
    }
    // With MODE 1, `b` takes the place of the culled `a`, and `side` a kernel of its own.
    let placed = kernels(&g, "split_short", 1);
    assert_eq!(placed[1].1, vec!["b".to_string(), "finish".to_string()], "{placed:?}");
    assert_eq!(placed[2].1, vec!["side".to_string()], "{placed:?}");
}

#[test]
fn a_pass_enabled_by_default_must_still_be_listed() {
    let g = graph(r#""listed": (kernels: [["make", "b", "finish"]])"#);
    let live = g.specialize(&BTreeMap::new()).unwrap();
    let e = Plan::new(&live, "listed").unwrap_err().to_string();
    assert!(
        e.contains("layout 'listed' puts pass 'a' in no kernel; it is enabled"),
        "{e}"
    );
}

#[test]
fn a_layout_like_another_takes_the_fields_it_does_not_give() {
    let g = graph(
        r#""listed": (kernels: [["make"], ["a", "finish"]], loops: Host, threads: 256, loop_guards: false),
           "same": (like: "listed", workgroup_size: 32),
           "third": (like: "same", kernels: [["make", "a", "finish"]], loops: InKernel)"#,
    );
    let (listed, same, third) = (
        g.layout("listed").unwrap(),
        g.layout("same").unwrap(),
        g.layout("third").unwrap(),
    );
    assert_eq!(same.kernels, listed.kernels);
    assert_eq!((same.workgroup_size, listed.workgroup_size), (32, 64));
    assert_eq!((same.threads, same.loop_guards), (Some(256), false));
    assert_eq!(kernels(&g, "same", 1), kernels(&g, "listed", 1));
    // Through a like of a like: its own kernels and loops, the rest from both before it.
    assert_eq!(third.kernels, vec![vec!["make", "a", "finish"]]);
    assert_eq!(
        (third.workgroup_size, third.threads, third.loop_guards),
        (32, Some(256), false)
    );
    assert!(matches!(third.loops, lightgraph_engine::ir::LoopMode::InKernel));
    for (layouts, message) in [
        (
            r#""listed": (kernels: [["make", "a", "finish"]]), "lost": (like: "listd")"#,
            "layout 'lost': is like 'listd', which is no layout of this graph (layouts: listed, lost)",
        ),
        (
            r#""listed": (like: "other"), "other": (like: "listed")"#,
            "go round a cycle",
        ),
    ] {
        let e = loaded(layouts).unwrap_err().to_string();
        assert!(e.starts_with("modes.ron:") && e.contains(message), "{e}");
    }
}
