//! Bad graphs give errors that name the file, line and column and the offending name.

use lightgraph_engine::{Graph, Layer, Vfs};
use std::path::PathBuf;

fn vfs() -> Vfs {
    Vfs::new(vec![Layer::Dir(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data"),
    )])
}

fn base() -> String {
    std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/collatz.ron")).unwrap()
}

fn error_of(text: &str) -> String {
    Graph::from_text(&vfs(), "bad.ron", text)
        .expect_err("the graph is refused")
        .to_string()
}

/// Line and column of the first occurrence of `needle` (1-based).
fn position(text: &str, needle: &str) -> (usize, usize) {
    let offset = text.find(needle).expect("needle in text");
    let before = &text[..offset];
    (
        before.matches('\n').count() + 1,
        offset - before.rfind('\n').map_or(0, |i| i + 1) + 1,
    )
}

#[test]
fn malformed_ron_names_line_and_column() {
    let text = base().replace("role: Loop,", "role: Loop");
    let e = error_of(&text);
    let (line, _) = position(&text, "role: Loop emits");
    assert!(
        e.starts_with(&format!("bad.ron:{line}:")),
        "error should point at line {line}: {e}"
    );
}

#[test]
fn unknown_pass_in_use() {
    let text = base().replace(
        "Pass(name: \"summarize\"",
        "Use(\"summarise\"), Pass(name: \"summarize2\"",
    );
    let e = error_of(&text);
    let (line, col) = position(&text, "\"summarise\"");
    assert!(e.contains("unknown pass 'summarise'"), "{e}");
    assert!(e.starts_with(&format!("bad.ron:{line}:{}", col + 1)), "{e}");
}

#[test]
fn unknown_resource() {
    let text = base().replace(
        "writes: [\"steps\", \"histogram\"]",
        "writes: [\"steps\", \"histogramm\"]",
    );
    let e = error_of(&text);
    assert!(
        e.contains("unknown resource 'histogramm'") && e.contains("'record'"),
        "{e}"
    );
    let (line, _) = position(&text, "\"histogramm\"");
    assert!(e.starts_with(&format!("bad.ron:{line}:")), "{e}");
}

#[test]
fn stream_type_mismatch() {
    let text = base().replace("\"done\": (item: \"Done\"", "\"done\": (item: \"Walk\"");
    let e = error_of(&text);
    assert!(
        e.contains("stream type mismatch") && e.contains("'Walk'") && e.contains("'Done'"),
        "{e}"
    );
}

#[test]
fn emits_into_unknown_stream() {
    let e = error_of(&base().replace("emits: [\"done\"]", "emits: [\"finished\"]"));
    assert!(e.contains("unknown stream 'finished'"), "{e}");
}

#[test]
fn unknown_default_layout() {
    let e = error_of(&base().replace("default_layout: \"fused\"", "default_layout: \"fastest\""));
    assert!(e.contains("default layout 'fastest'"), "{e}");
}

#[test]
fn step_after_loop_is_refused() {
    let text = base().replace(
        "Pass(name: \"record\"",
        "Pass(name: \"after\", item: \"Walk\", source: \"collatz.wgsl\", role: Step, writes: [\"steps\"]), Pass(name: \"record\"",
    );
    let e = error_of(&text);
    assert!(e.contains("'after'") && e.contains("loop"), "{e}");
}

#[test]
fn reserved_names_are_refused() {
    let e = error_of(
        &base()
            .replace("\"scratch\": (ty", "\"lg_scratch\": (ty")
            .replace("[\"scratch\"]", "[\"lg_scratch\"]"),
    );
    assert!(e.contains("'lg_scratch'"), "{e}");
}
