//! Derived constants, constant checks, catalog resources brought by operators, and loop groups kept whole by
//! culling (graph loading and specialisation only; no GPU).

use lightgraph_engine::{ConstValue, Graph, Layer, Vfs};
use std::collections::BTreeMap;
use std::path::PathBuf;

fn vfs() -> Vfs {
    Vfs::new(vec![Layer::Dir(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data"),
    )])
}

/// The Collatz test graph with `derived` declarations and a pass list edited by `edit`.
fn collatz(derived: &str, edit: impl Fn(String) -> String) -> String {
    let text =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/collatz.ron")).unwrap();
    let text = text.replace(
        r#"constants: { "N": U32(1000), "BINS": U32(64) },"#,
        &format!(r#"constants: {{ "N": U32(1000), "BINS": U32(64) }}, derived: {{ {derived} }},"#),
    );
    edit(text)
}

fn constants(given: &[(&str, ConstValue)]) -> BTreeMap<String, ConstValue> {
    given.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

#[test]
fn derived_constants_follow_the_others_and_can_be_given() {
    let text = collatz(r#""HALF": "N / 2", "QUARTER": "HALF / 2""#, |t| t);
    let graph = Graph::from_text(&vfs(), "derived.ron", &text).unwrap();
    let live = graph.specialize(&constants(&[("N", ConstValue::U32(7))])).unwrap();
    // Rounded up like counts: 3.5 -> 4, then 4 / 2 = 2.
    assert_eq!(live.constants["HALF"], ConstValue::U32(4));
    assert_eq!(live.constants["QUARTER"], ConstValue::U32(2));
    let given = graph.specialize(&constants(&[("HALF", ConstValue::U32(100))])).unwrap();
    assert_eq!(given.constants["QUARTER"], ConstValue::U32(50));
    let e = graph
        .specialize(&constants(&[("HALF", ConstValue::F32(1.0))]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("'HALF' is a derived u32 but was given as f32"), "{e}");
}

#[test]
fn a_derived_constant_naming_an_unknown_constant_is_located() {
    let text = collatz(r#""HALF": "M / 2""#, |t| t);
    let graph = Graph::from_text(&vfs(), "derived.ron", &text).unwrap();
    let e = graph.specialize(&BTreeMap::new()).unwrap_err().to_string();
    assert!(e.starts_with("derived.ron:"), "{e}");
    assert!(e.contains("derived constant 'HALF'") && e.contains("'M'"), "{e}");
    let clash = collatz(r#""N": "BINS""#, |t| t);
    let e = Graph::from_text(&vfs(), "derived.ron", &clash).unwrap_err().to_string();
    assert!(e.contains("'N' is derived and also declared as a constant"), "{e}");
}

#[test]
fn a_failing_constant_check_is_an_error_at_its_declaration_with_the_values() {
    let text = collatz("", |t| {
        t.replace(
            r#"derived: {  },"#,
            "derived: {  },\n    checks: { \"BINS <= 64 && BINS >= 1\": \"BINS is 1 to 64\" },",
        )
    });
    assert!(text.contains("checks"), "the test graph changed");
    let graph = Graph::from_text(&vfs(), "checks.ron", &text).unwrap();
    graph.specialize(&constants(&[("BINS", ConstValue::U32(64))])).unwrap();
    let e = graph
        .specialize(&constants(&[("BINS", ConstValue::U32(65))]))
        .unwrap_err()
        .to_string();
    let line = text.lines().position(|l| l.contains("checks")).unwrap() + 1;
    assert!(e.starts_with(&format!("checks.ron:{line}:")), "{e}");
    assert!(
        e.contains("'BINS <= 64 && BINS >= 1' does not hold (BINS = 65): BINS is 1 to 64"),
        "{e}"
    );
    let bad = text.replace("BINS <= 64 &&", "BINS <= &&");
    let e = Graph::from_text(&vfs(), "checks.ron", &bad).unwrap_err().to_string();
    assert!(e.contains("check 'BINS <= && BINS >= 1'"), "{e}");
}

#[test]
fn a_loop_pass_that_only_ends_the_loop_is_not_culled() {
    let text = collatz("", |t| {
        t.replace(
            r#"role: Loop, emits: ["done"]),"#,
            r#"role: Loop, emits: ["done"]),
        Pass(name: "until_one", item: "Walk", source: "collatz.wgsl", role: Loop),"#,
        )
    });
    let graph = Graph::from_text(&vfs(), "loop.ron", &text).unwrap();
    let live = graph.specialize(&BTreeMap::new()).unwrap();
    assert!(!live.is_culled("until_one"), "{:?}", live.culled);
    // A pass that feeds nothing outside a loop still goes.
    assert!(live.is_culled("unused"), "{:?}", live.culled);
}
