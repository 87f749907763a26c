//! Graphs that extend graphs (`extends`), and layouts that leave out the passes the constants
//! disable (graph loading and planning only; no GPU).

use lightgraph_engine::{ConstValue, Graph, Layer, Plan, Vfs};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A file system of the test data behind a fresh folder holding `files`.
fn vfs_with(test: &str, files: &[(&str, &str)]) -> Vfs {
    let dir = std::env::temp_dir().join(format!("lg-extends-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    Vfs::new(vec![
        Layer::Dir(dir),
        Layer::Dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")),
    ])
}

/// The 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

const EXTENDING: &str = r#"(
    extends: "collatz.ron",
    name: "walks",
    constants: { "N": U32(10) },
    passes: [
        Replace("summarize", [Pass(name: "summarize", item: "Bin", source: "collatz.wgsl",
                role: Start(over: "BINS / 2"), reads: ["histogram"], writes: ["summary"])]),
        Remove("unused"),
    ],
    layouts: {
        "halves": Layout(kernels: [["seed", "step", "record"], ["summarize"]], workgroup_size: 32),
        "fused_again": From("fused"),
        "fused_narrow": Layout(like: "fused", workgroup_size: 16),
        "two_entries": Remove,
    },
)
"#;

#[test]
fn an_extending_graph_overrides_constants_passes_and_layouts() {
    let vfs = vfs_with("overrides", &[("walks.ron", EXTENDING)]);
    let graph = Graph::load(&vfs, "walks.ron").unwrap();
    assert_eq!(graph.name, "walks");
    assert_eq!(graph.description, "Collatz walks (engine test)");
    assert_eq!(graph.constants["N"], ConstValue::U32(10));
    assert_eq!(graph.constants["BINS"], ConstValue::U32(64));
    let names: Vec<&str> = graph.declared.passes.iter().map(|p| p.decl.name.as_str()).collect();
    assert_eq!(names, ["seed", "step", "record", "summarize"]);
    // The replaced pass is the extending file's, the others stay the base's.
    let origin = |name: &str| {
        graph
            .declared
            .passes
            .iter()
            .find(|p| p.decl.name == name)
            .unwrap()
            .origin
            .clone()
    };
    assert_eq!(origin("summarize"), "walks.ron");
    assert_eq!(origin("seed"), "collatz.ron");
    assert!(graph.layouts.contains_key("fused") && !graph.layouts.contains_key("two_entries"));
    assert_eq!(Plan::new(&graph, "halves").unwrap().layout.workgroup_size, 32);
    Plan::new(&graph, "fused_again").unwrap();
    // A layout like the base's: its kernels, this file's workgroup size.
    assert_eq!(graph.layouts["fused_narrow"].kernels, graph.layouts["fused"].kernels);
    assert_eq!(Plan::new(&graph, "fused_narrow").unwrap().layout.workgroup_size, 16);
}

#[test]
fn an_edit_of_what_the_base_lacks_is_an_error_in_the_extending_file() {
    let text = EXTENDING.replace(r#"Remove("unused")"#, r#"Remove("unsued")"#);
    let vfs = vfs_with("edit", &[("walks.ron", &text)]);
    let e = Graph::load(&vfs, "walks.ron").unwrap_err().to_string();
    let line = line_of(&text, "unsued");
    assert!(e.starts_with(&format!("walks.ron:{line}:")), "{e}");
    assert!(
        e.contains("no entry 'unsued' to edit in the graph it extends (collatz.ron"),
        "{e}"
    );
    let text = EXTENDING.replace(r#"From("fused")"#, r#"From("fussed")"#);
    let vfs = vfs_with("layout_edit", &[("walks.ron", &text)]);
    let e = Graph::load(&vfs, "walks.ron").unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("walks.ron:{}:", line_of(&text, "fussed"))),
        "{e}"
    );
    assert!(e.contains("no layout 'fussed' in the graph it extends"), "{e}");
}

#[test]
fn an_error_of_the_base_points_into_the_base() {
    let vfs = vfs_with("base_error", &[("walks.ron", EXTENDING)]);
    let graph = Graph::load(&vfs, "walks.ron").unwrap();
    // The base's layout `missing_pass` leaves out the enabled pass `summarize`.
    let e = Plan::new(&graph, "missing_pass").unwrap_err().to_string();
    let base =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/collatz.ron")).unwrap();
    assert!(
        e.starts_with(&format!("collatz.ron:{}:", line_of(&base, "\"missing_pass\""))),
        "{e}"
    );
    assert!(e.contains("puts pass 'summarize' in no kernel; it is enabled"), "{e}");
}

#[test]
fn a_missing_base_is_an_error_at_its_name() {
    let text = EXTENDING.replace("\"collatz.ron\"", "\"collatz2.ron\"");
    let vfs = vfs_with("missing", &[("walks.ron", &text)]);
    let e = Graph::load(&vfs, "walks.ron").unwrap_err().to_string();
    assert!(e.starts_with("walks.ron:2:15:"), "{e}");
    assert!(e.contains("cannot read the base graph: collatz2.ron: not found"), "{e}");
}

#[test]
fn a_cycle_of_extends_is_an_error_naming_the_files() {
    let a = r#"(extends: "b.ron", name: "a")"#;
    let b = "(\n    extends: \"a.ron\",\n)\n";
    let vfs = vfs_with("cycle", &[("a.ron", a), ("b.ron", b)]);
    let e = Graph::load(&vfs, "a.ron").unwrap_err().to_string();
    assert!(e.starts_with("b.ron:2:15:"), "{e}");
    assert!(e.contains("extends closes a cycle: a.ron → b.ron → a.ron"), "{e}");
}

#[test]
fn a_layout_may_leave_out_the_passes_the_constants_disable() {
    let text = r#"(
    extends: "collatz.ron",
    passes: [Replace("summarize", [Pass(name: "summarize", item: "Bin", source: "collatz.wgsl",
             role: Start(over: "BINS"), reads: ["histogram"], writes: ["summary"], enabled: "SUMMARY")])],
    constants: { "SUMMARY": Bool(false) },
    outputs: ["steps"],
    layouts: { "walks_only": Layout(kernels: [["seed", "step", "record"]]) },
)
"#;
    let vfs = vfs_with("disabled", &[("walks.ron", text)]);
    let graph = Graph::load(&vfs, "walks.ron").unwrap();
    Plan::new(&graph, "walks_only").unwrap();
    let mut on = BTreeMap::new();
    on.insert("SUMMARY".to_string(), ConstValue::Bool(true));
    let with = Graph::load(&vfs, "walks.ron").unwrap().specialize(&on).unwrap();
    // Enabled, it contributes to no output and is culled all the same: give it one.
    assert!(with.is_culled("summarize"));
    let text = text
        .replace(r#"outputs: ["steps"],"#, "")
        .replace("Bool(false)", "Bool(true)");
    let vfs = vfs_with("enabled", &[("walks.ron", &text)]);
    let with = Graph::load(&vfs, "walks.ron").unwrap();
    let e = Plan::new(&with, "walks_only").unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("walks.ron:{}:", line_of(&text, "\"walks_only\""))),
        "{e}"
    );
    assert!(
        e.contains("layout 'walks_only' puts pass 'summarize' in no kernel; it is enabled, and a layout may leave out only the passes the constants disable"),
        "{e}"
    );
}
