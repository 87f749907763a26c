//! The layout cache (lightgraph::layout_cache): `render --layout auto` stores its winner; a
//! render of the same key without `--layout`, and `--layout auto` again, take it without
//! measuring; a render of another size does not; `--retune` measures again; a cache file that
//! cannot be read is a warning naming it, and the render goes on with the graph's default.

use crate::cli::temp_dir;
use std::path::Path;
use std::process::Command;

/// `lightgraph render` of the ambient-occlusion graph on the diffuse box (2 frames) with the
/// layout cache in `cache` and `extra` arguments; its stderr (the render must succeed).
fn render(cache: &Path, extra: &[&str]) -> String {
    render_graph(cache, "ao", extra)
}

/// [`render`] of `graph`.
fn render_graph(cache: &Path, graph: &str, extra: &[&str]) -> String {
    let out = cache.join("render.exr");
    let base = [
        "render",
        "--graph",
        graph,
        "--scene",
        "cornell-diffuse",
        "--frames",
        "2",
        "--force",
    ];
    let output = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args(base)
        .args(["--tune-time", "30ms", "--out", out.to_str().unwrap()])
        .args(extra)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("LIGHTGRAPH_CACHE", cache)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr).to_string();
    assert!(output.status.success(), "{stderr}");
    stderr
}

#[test]
fn layout_auto_stores_its_winner_and_renders_of_the_same_key_take_it() {
    let cache = temp_dir("layout-cache");
    let small = ["--res", "16x12"];
    let measured = render(&cache, &[&small[..], &["--layout", "auto"]].concat());
    assert!(measured.contains("measuring every legal layout"), "{measured}");
    assert!(measured.contains("stored in the layout cache"), "{measured}");
    let winner = measured
        .lines()
        .find_map(|l| l.strip_prefix("winner: "))
        .and_then(|l| l.rsplit_once(" ("))
        .map(|(name, _)| name.to_string())
        .expect("a winner line");
    let from_cache = format!("layout {winner} from the layout cache");
    let plain = render(&cache, &small);
    assert!(plain.contains(&from_cache), "{plain}");
    assert!(plain.contains(&format!("graph ao layout {winner} |")), "{plain}");
    let again = render(&cache, &[&small[..], &["--layout", "auto"]].concat());
    assert!(again.contains(&from_cache) && !again.contains("measuring"), "{again}");
    let other = render(&cache, &["--res", "8x8"]);
    assert!(
        !other.contains("layout cache") && other.contains("graph ao layout AOsk |"),
        "{other}"
    );
    let retuned = render(&cache, &[&small[..], &["--layout", "auto", "--retune"]].concat());
    assert!(retuned.contains("measuring every legal layout"), "{retuned}");
    std::fs::write(cache.join("layouts.ron"), "[(key: (graph: 3").unwrap();
    let broken = render(&cache, &small);
    assert!(
        broken.contains("warning: ") && broken.contains("layouts.ron:1:"),
        "{broken}"
    );
    assert!(broken.contains("graph ao layout AOsk |"), "{broken}");
    std::fs::remove_dir_all(&cache).ok();
}

#[test]
fn a_winner_is_found_when_the_default_layout_hints_another_bvh() {
    // A copy of ao whose default layout hints the BVH2: a render without --layout builds the
    // BVH2, --layout auto measures on the CWBVH; the render still finds the winner (the key
    // holds the BVH asked for, `auto`) and builds the BVH it was measured with.
    let cache = temp_dir("layout-cache-bvh");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/graphs/ao.ron")).unwrap();
    let fused = r#"kernels: [["ao_primary", "ao_occlusion"], ["accumulate"]],"#;
    assert!(text.contains(fused));
    let hinted = text.replacen(fused, &format!("{fused}\n            hints: {{\"bvh\": \"bvh2\"}},"), 1);
    let graph = cache.join("ao-bvh2.ron");
    std::fs::write(&graph, hinted).unwrap();
    let graph = graph.to_str().unwrap();
    let small = ["--res", "16x12"];
    let measured = render_graph(&cache, graph, &[&small[..], &["--layout", "auto"]].concat());
    assert!(measured.contains("stored in the layout cache"), "{measured}");
    let plain = render_graph(&cache, graph, &small);
    assert!(plain.contains("from the layout cache"), "{plain}");
    let stored = std::fs::read_to_string(cache.join("layouts.ron")).unwrap();
    assert!(
        stored.contains(r#"bvh: "auto""#) && stored.contains(r#"bvh: Some("cwbvh")"#),
        "{stored}"
    );
}
