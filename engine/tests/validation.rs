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

/// The Collatz graph with `extra` appended to its passes.
fn with_passes(extra: &str) -> String {
    base().replace(
        "        Pass(name: \"unused\"",
        &format!("        {extra}\n        Pass(name: \"unused\""),
    )
}

#[test]
fn a_constant_condition_culls_and_says_why() {
    let text = base().replace(
        "Pass(name: \"summarize\", item: \"Bin\",",
        "Pass(name: \"summarize\", item: \"Bin\", enabled: \"BINS > 64\",",
    );
    let e = error_of(&text);
    assert!(
        e.contains("output 'summary' has no live writer")
            && e.contains("'summarize' disabled: `BINS > 64` is 0 with BINS = 64u"),
        "{e}"
    );
    let (line, _) = position(&text, "outputs: [\"steps\", \"summary\"]");
    assert!(e.starts_with(&format!("bad.ron:{line}:")), "{e}");
}

#[test]
fn a_graph_with_every_pass_culled_is_an_error() {
    let text = base().replace("role: ", "enabled: \"0\", role: ");
    let e = error_of(&text);
    assert!(
        e.contains("every pass of graph 'collatz' is culled") && e.contains("'seed' disabled"),
        "{e}"
    );
}

#[test]
fn an_unknown_name_in_a_condition_is_an_error_once_constants_are_known() {
    let text = base().replace(
        "Pass(name: \"summarize\", item: \"Bin\",",
        "Pass(name: \"summarize\", item: \"Bin\", enabled: \"SUMMARY\",",
    );
    // Loading keeps the pass (the host's constants are not known yet) ...
    let g = Graph::from_text(&vfs(), "bad.ron", &text).unwrap();
    // ... specialising names the unknown constant where the condition stands.
    let e = g.specialize(&Default::default()).unwrap_err().to_string();
    let (line, _) = position(&text, "\"SUMMARY\"");
    assert!(
        e.starts_with(&format!("bad.ron:{line}:")) && e.contains("unknown constant 'SUMMARY'"),
        "{e}"
    );
}

#[test]
fn operators_are_checked() {
    let cases = [
        (
            "Scan(name: \"sums\", input: \"nowhere\", over: \"N\"),",
            "operator 'sums' uses unknown resource 'nowhere'",
        ),
        (
            "Scan(name: \"sums\", input: \"histogram\", output: \"summary\", over: \"BINS\"),",
            "",
        ),
        (
            "Count(name: \"tally\", keys: \"steps\", counts: \"histogram\", slots: \"steps\", over: \"N\", counted: \"summary\"),",
            "",
        ),
        (
            "Scatter(name: \"sort\", keys: \"steps\", slots: \"scratch\", offsets: \"summary\", input: \"steps\", output: \"floats\", over: \"N\"),",
            "operator 'sort' moves 'steps' (u32) into 'floats' (f32); both must hold the same type",
        ),
        (
            "Scatter(name: \"order\", keys: \"steps\", slots: \"scratch\", offsets: \"summary\", output: \"floats\", over: \"N\"),",
            "needs u32 elements in 'floats', which holds 'f32'",
        ),
        (
            "Scatter(name: \"order\", keys: \"steps\", slots: \"scratch\", offsets: \"summary\", output: \"histogram\", over: \"N\"),",
            "",
        ),
        (
            "Gather(name: \"fetch\", indices: \"steps\", input: \"steps\", output: \"floats\", over: \"N\"),",
            "operator 'fetch' moves 'steps' (u32) into 'floats' (f32); both must hold the same type",
        ),
        (
            "Gather(name: \"fetch\", indices: \"floats\", input: \"steps\", output: \"scratch\", over: \"N\"),",
            "needs u32 elements in 'floats', which holds 'f32'",
        ),
        ("Scan(name: \"sums\", input: \"floats\", over: \"N\"),", ""),
        (
            "Scan(name: \"sums\", input: \"floats\", output: \"weights\", over: \"N\"),",
            "",
        ),
        (
            "Scan(name: \"sums\", input: \"floats\", output: \"steps\", over: \"N\"),",
            "operator 'sums' sums 'floats' (f32) into 'steps' (u32); both must hold u32 (or atomic<u32>) or both f32",
        ),
        (
            "Scan(name: \"sums\", input: \"histogram\", output: \"floats\", over: \"BINS\"),",
            "operator 'sums' sums 'histogram' (atomic<u32>) into 'floats' (f32); both must hold",
        ),
        (
            "Scan(name: \"sums\", input: \"points\", over: \"N\"),",
            "operator 'sums' (exclusive scan) needs u32 or f32 elements in 'points', which holds 'vec2<f32>'",
        ),
        (
            "Clear(name: \"wipe\", buffer: \"steps\"), Clear(name: \"wipe\", buffer: \"steps\"),",
            "pass 'wipe' appears twice",
        ),
        (
            "Scan(name: \"sums\", input: \"steps\", over: \"N\", counted: \"floats\"),",
            "'sums' is counted by 'floats', whose elements are 'f32'; a counter is a u32 or atomic<u32>",
        ),
    ];
    for (entry, want) in cases {
        let text = with_passes(entry).replace(
            "\"scratch\": (ty: \"u32\", count: \"BINS\"),",
            "\"scratch\": (ty: \"u32\", count: \"BINS\"), \"floats\": (ty: \"f32\", count: \"N\"), \"weights\": (ty: \"f32\", count: \"N\"), \"points\": (ty: \"vec2<f32>\", count: \"N\"),",
        );
        match Graph::from_text(&vfs(), "bad.ron", &text) {
            Ok(_) => assert!(want.is_empty(), "{entry}: accepted, expected '{want}'"),
            Err(e) => {
                let e = e.to_string();
                assert!(!want.is_empty() && e.contains(want), "{entry}: {e}");
                assert!(e.starts_with("bad.ron:"), "{e}");
            }
        }
    }
}

#[test]
fn layouts_do_not_list_operators() {
    let text = with_passes("Clear(name: \"wipe\", buffer: \"scratch\"),").replace(
        "\"fused\": (kernels: [[\"seed\", \"step\", \"record\"], [\"summarize\"]]),",
        "\"fused\": (kernels: [[\"seed\", \"step\", \"record\"], [\"summarize\"], [\"wipe\"]]),",
    );
    let g = Graph::from_text(&vfs(), "bad.ron", &text).unwrap();
    let e = lightgraph_engine::Plan::new(&g, "fused").unwrap_err().to_string();
    assert!(e.contains("names operator 'wipe'; operators run on their own"), "{e}");
}

#[test]
fn parameters_are_checked() {
    let text = base().replace("constants: {", "parameters: { \"SCALE\": F32(1.0) },\n    constants: {");
    let sized = text.replace(
        "\"steps\": (ty: \"u32\", count: \"N\")",
        "\"steps\": (ty: \"u32\", count: \"N * SCALE\")",
    );
    let e = error_of(&sized);
    assert!(e.contains("resource 'steps' is sized by parameter 'SCALE'"), "{e}");
    let twice = text.replace("parameters: { \"SCALE\"", "parameters: { \"N\": U32(3), \"SCALE\"");
    let e = error_of(&twice);
    assert!(e.contains("'N' is both a constant and a parameter"), "{e}");
}

#[test]
fn outputs_must_outlive_the_frame() {
    let text = base().replace(
        "\"summary\": (ty: \"u32\", count: \"BINS\"),",
        "\"summary\": (ty: \"u32\", count: \"BINS\", scope: Transient),",
    );
    let e = error_of(&text);
    assert!(e.contains("output 'summary' is Transient"), "{e}");
    let cleared = base().replace(
        "\"summary\": (ty: \"u32\", count: \"BINS\"),",
        "\"summary\": (ty: \"u32\", count: \"BINS\", clear: true),",
    );
    let e = error_of(&cleared);
    assert!(
        e.contains("resource 'summary' has clear: true but is not Transient"),
        "{e}"
    );
}

#[test]
fn an_operator_condition_is_located_where_it_stands() {
    let text = with_passes("Clear(name: \"wipe\", buffer: \"scratch\", enabled: \"WIPE > 1\"),").replace(
        "outputs: [\"steps\", \"summary\"]",
        "outputs: [\"steps\", \"summary\", \"scratch\"]",
    );
    let g = Graph::from_text(&vfs(), "bad.ron", &text).unwrap();
    let e = g.specialize(&Default::default()).unwrap_err().to_string();
    let (line, _) = position(&text, "\"WIPE > 1\"");
    assert!(
        e.starts_with(&format!("bad.ron:{line}:")) && e.contains("unknown constant 'WIPE'"),
        "{e}"
    );
    let bad = with_passes("Clear(name: \"wipe\", buffer: \"scratch\", enabled: \"WIPE >\"),");
    let e = error_of(&bad);
    let (line, _) = position(&bad, "\"WIPE >\"");
    assert!(
        e.starts_with(&format!("bad.ron:{line}:")) && e.contains("operator 'wipe': enabled"),
        "{e}"
    );
}

#[test]
fn measured_values_are_checked_and_read_the_ratio() {
    let measured = |value: &str| {
        base()
            .replace("\"BINS\": U32(64) },", "\"BINS\": U32(64), \"SCALE\": F32(1.0) },")
            .replace(
                "    counters: [",
                &format!("    measured: {{ \"SCALE\": (ratio: (\"iterations\", \"walks\"), value: \"{value}\") }},\n    counters: ["),
            )
    };
    let e = error_of(&measured("1 + 2 * (RATIO < WIDTH)"));
    assert!(
        e.contains("measured constant 'SCALE': value uses 'WIDTH', which is neither RATIO nor a constant"),
        "{e}"
    );
    let e = error_of(&measured("1 + * RATIO"));
    assert!(e.contains("measured constant 'SCALE': value:"), "{e}");
    let g = Graph::from_text(&vfs(), "good.ron", &measured("1 + 2 * (RATIO < BINS / 128)")).unwrap();
    let m = &g.measured["SCALE"];
    let constants = [("BINS".to_string(), lightgraph_engine::ConstValue::U32(64))].into();
    // BINS / 128 = 0.5: a ratio of 0.25 is below it, 0.75 is not, and no walks at all reads 0.
    assert_eq!(m.value_from(1, 4, &constants), Ok(3.0));
    assert_eq!(m.value_from(3, 4, &constants), Ok(1.0));
    assert_eq!(m.value_from(5, 0, &constants), Ok(3.0));
    let plain = lightgraph_engine::ir::MeasuredDecl {
        value: None,
        ..m.clone()
    };
    assert_eq!(plain.value_from(3, 4, &constants), Ok(0.75));
    assert!(
        plain
            .value_from(3, 0, &constants)
            .unwrap_err()
            .contains("counter 'walks' stayed 0")
    );
}
