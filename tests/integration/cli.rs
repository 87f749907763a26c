//! The command line: a small render writes an EXR (with metadata) and a PNG; `explain`
//! prints kernels and resources; bad input exits non-zero with an error naming the file,
//! line and column or the missing name, and never panics.

use crate::common::data;
use std::path::PathBuf;
use std::process::{Command, Output};

pub(crate) fn lightgraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        // No test takes a layout from a cache of the machine's own (tests/integration/layout_cache.rs).
        .env(
            "LIGHTGRAPH_CACHE",
            std::env::temp_dir().join(format!("lightgraph-cache-{}", std::process::id())),
        )
        .output()
        .expect("the binary runs")
}

pub(crate) fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs with bad input: exit code 1, an `error:` line, no panic; returns stderr.
pub(crate) fn fails(args: &[&str]) -> String {
    let out = lightgraph(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail cleanly: {stderr}");
    assert!(stderr.contains("error:"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    stderr
}

/// A copy of graphs/pt.ron with one replacement, written to a temporary file.
fn pt_variant(name: &str, from: &str, to: &str) -> (String, PathBuf) {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/graphs/pt.ron")).unwrap();
    assert!(text.contains(from), "graphs/pt.ron contains {from}");
    let changed = text.replacen(from, to, 1);
    let path = temp_dir(name).join(format!("{name}.ron"));
    std::fs::write(&path, &changed).unwrap();
    (changed, path)
}

/// The error of rendering the graph file `path` (8 x 8, one frame), which must fail cleanly.
fn render_graph_fails(path: &std::path::Path) -> String {
    fails(&[
        "render",
        "--graph",
        path.to_str().unwrap(),
        "--res",
        "8x8",
        "--frames",
        "1",
    ])
}

fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).expect("needle")].matches('\n').count() + 1
}

/// Asserts that `err` points at `file`'s line where `text` holds `needle` (`FILE:LINE:`).
fn assert_at_line(err: &str, file: &str, text: &str, needle: &str) {
    let at = format!("{file}:{}:", line_of(text, needle));
    assert!(err.contains(&at), "not at {at}: {err}");
}

#[test]
fn render_writes_exr_with_metadata_and_png() {
    let dir = temp_dir("render");
    let exr = dir.join("cornell.exr");
    let out = lightgraph(&[
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "24x16",
        "--frames",
        "2",
        "--seed",
        "9",
        "--out",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("cornell.png").is_file());
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |size, _| vec![[0f32; 3]; size.width() * size.height()],
        |pixels: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[pos.y() * 24 + pos.x()] = [r, g, b]
        },
    )
    .unwrap();
    let layer = &image.layer_data;
    assert_eq!((layer.size.width(), layer.size.height()), (24, 16));
    assert!(
        layer.channel_data.pixels.iter().any(|p| p[0] > 0.0),
        "the image is not black"
    );
    let attrs = &layer.attributes.other;
    let get = |k: &str| {
        attrs
            .get(&exr::meta::attribute::Text::from(format!("lightgraph.{k}").as_str()))
            .map(|v| format!("{v:?}"))
    };
    for (k, v) in [
        ("graph", "pt"),
        ("layout", "NaivePTsk"),
        ("scene", "cornell-diffuse"),
        ("samples_per_pixel", "2"),
    ] {
        assert!(get(k).is_some_and(|s| s.contains(v)), "metadata {k} = {:?}", get(k));
    }
    assert!(get("seconds").is_some());
}

#[test]
fn each_layout_gets_the_bvh_measured_fastest_in_it_unless_one_is_named() {
    let text = |args: &[&str]| {
        let out = lightgraph(args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let auto = text(&["explain", "--graph", "lt", "--res", "16x16"]);
    assert!(auto.contains("layout LTsk: BVH bvh2"), "{auto}");
    assert!(auto.contains("layout LTmk: BVH cwbvh"), "{auto}");
    let named = text(&[
        "explain", "--graph", "lt", "--layout", "LTsk", "--res", "16x16", "--bvh", "cwbvh",
    ]);
    assert!(named.contains("layout LTsk: BVH cwbvh"), "{named}");
    let (_, path) = pt_variant(
        "bvh-hint",
        "\"NaivePTsk\": (",
        "\"NaivePTsk\": (\n            hints: {\"bvh\": \"octree\"},",
    );
    let graph = path.to_str().unwrap();
    let err = fails(&["explain", "--graph", graph, "--layout", "NaivePTsk", "--res", "16x16"]);
    assert!(err.contains("layout 'NaivePTsk'") && err.contains("octree"), "{err}");
    // Named, the hint is not read.
    text(&[
        "explain",
        "--graph",
        graph,
        "--layout",
        "NaivePTsk",
        "--res",
        "16x16",
        "--bvh",
        "bvh2",
    ]);
}

#[test]
fn explain_outline_prints_the_frame_as_loops_with_each_steps_function_and_resources() {
    let outline = |extra: &[&str]| {
        let out = lightgraph(&[&["explain", "--graph", "vcm", "--res", "16x16", "--outline"], extra].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let text = outline(&[]);
    // Light sub-paths with their loop, the cache and grid built by operators, then the camera
    // sub-paths that connect and merge, each step with its function and file.
    let order = [
        " 1. for each of LVC_LIGHT_STARTS LightPath:",
        "vcm_light_generate       fn vcm_light_generate (shaders/vcm/vcm.wgsl)",
        "      repeat while the item goes on:",
        "light_trace              fn light_trace (shaders/lt/trace.wgsl)",
        "for each ShadowRay emitted into 'splat':",
        "exclusive scan 'grid_starts'  < grid_counts  > grid_first",
        "for each of PATHS VcmPath:",
        "vcm_gather               fn vcm_gather (shaders/vcm/camera.wgsl)",
        "for each of PIXELS Pixel:",
    ];
    let mut at = 0;
    for line in order {
        let found = text[at..]
            .find(line)
            .unwrap_or_else(|| panic!("{line:?} after byte {at}:\n{text}"));
        at += found + line.len();
    }
    // The scene's resources are left out; the graph's own are listed.
    assert!(text.contains("> film") && !text.contains("primitives"), "{text}");
    // A constant that switches the merges off leaves the grid out, and says why.
    let connections = outline(&["--set", "VCM_MERGE=false"]);
    assert!(!connections.contains("exclusive scan 'grid_starts'"), "{connections}");
    assert!(
        connections.contains("left out:\n") && connections.contains("  vcm_gather: disabled:"),
        "{connections}"
    );
    // --outline shows no layout, so it takes none (a usage error of the argument parser).
    let out = lightgraph(&["explain", "--graph", "vcm", "--outline", "--layout", "VCMsk"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("'--outline' cannot be used with '--layout"),
        "{err}"
    );
}

#[test]
fn explain_prints_kernels_and_resources_of_each_layout() {
    let out = lightgraph(&["explain", "--graph", "pt", "--res", "32x32"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for needle in [
        "layout 'NaivePTsk'",
        "layout 'NaivePTmk'",
        "layout 'WavefrontPT'",
        "k0_generate_trace_logic",
        "k1_trace_logic_material",
        "queue 'shadow'",
        "compacted",
        "resources:",
        "film:",
        "GPU memory",
    ] {
        assert!(text.contains(needle), "explain output lacks {needle:?}:\n{text}");
    }
}

#[test]
fn explain_shows_the_layout_with_its_overrides() {
    let text = |extra: &[&str]| {
        let mut args = vec![
            "explain",
            "--graph",
            "pt",
            "--layout",
            "StreamingPTmk2",
            "--res",
            "32x32",
        ];
        args.extend_from_slice(extra);
        let out = lightgraph(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let own = text(&[]);
    assert!(own.contains("workgroup 64") && own.contains("loop guards off"), "{own}");
    let overridden = text(&["--workgroup", "128", "--loop-guards", "on"]);
    assert!(
        overridden.contains("workgroup 128") && overridden.contains("loop guards on"),
        "{overridden}"
    );
}

#[test]
fn malformed_ron_graph() {
    let path = temp_dir("malformed").join("malformed.ron");
    std::fs::write(&path, "(\n    name: \"broken\",\n    passes: [Use(\"generate\"\n)").unwrap();
    let err = render_graph_fails(&path);
    assert!(err.contains("malformed.ron:4:"), "{err}");
}

#[test]
fn a_constant_named_like_a_host_flag_is_an_error_at_its_line() {
    // A true Bool constant is a preprocessor flag too: named like a scene feature it would
    // compile that feature's code into kernels of a scene without it.
    let (text, path) = pt_variant(
        "flag-constant",
        "constants: { \"FRAME_SLOTS\": Bool(true) }",
        "constants: { \"FRAME_SLOTS\": Bool(true), \"TEXTURES\": Bool(true) }",
    );
    let err = render_graph_fails(&path);
    assert!(
        err.contains("constant 'TEXTURES' has the name of a flag the host sets"),
        "{err}"
    );
    assert_at_line(&err, "flag-constant.ron", &text, "\"TEXTURES\"");
}

#[test]
fn unknown_pass() {
    let (text, path) = pt_variant("unknown-pass", "Use(\"shadow\")", "Use(\"shadowz\")");
    let err = render_graph_fails(&path);
    assert!(err.contains("unknown pass 'shadowz'"), "{err}");
    assert_at_line(&err, "unknown-pass.ron", &text, "\"shadowz\"");
}

#[test]
fn use_with_an_unknown_pass_or_resource_is_an_error_at_its_line() {
    let (text, path) = pt_variant(
        "use-with-pass",
        "Use(\"shadow\")",
        "UseWith(name: \"shadowz\", reads: [\"film\"])",
    );
    let err = render_graph_fails(&path);
    assert!(err.contains("unknown pass 'shadowz'"), "{err}");
    assert_at_line(&err, "use-with-pass.ron", &text, "\"shadowz\"");
    // Writes it adds are checked as a catalog's are: a resource no file declares is an error.
    let (_, path) = pt_variant(
        "use-with-resource",
        "Use(\"shadow\")",
        "UseWith(name: \"shadow\", writes: [\"no_such_buffer\"])",
    );
    let err = render_graph_fails(&path);
    assert!(err.contains("unknown resource 'no_such_buffer'"), "{err}");
    // Reads of a catalog pass that derives its reads are not listed.
    let (text, path) = pt_variant(
        "use-with-derived",
        "Use(\"shadow\")",
        "UseWith(name: \"shadow\", reads: [\"film\"])",
    );
    let err = render_graph_fails(&path);
    assert!(err.contains("its catalog derives them from the WGSL"), "{err}");
    assert_at_line(&err, "use-with-derived.ron", &text, "[\"film\"]");
}

#[test]
fn unknown_resource() {
    // Without the film catalog, nothing declares the film the path-tracing passes write.
    let (_, path) = pt_variant(
        "unknown-resource",
        "catalogs: [\"passes/pt.ron\", \"passes/film.ron\"],\n    passes: [Use(\"generate\"), Use(\"trace\"), Use(\"logic\"), Use(\"material\"), Use(\"shadow\"), Use(\"accumulate\")],",
        "catalogs: [\"passes/pt.ron\"],\n    passes: [Use(\"generate\"), Use(\"trace\"), Use(\"logic\"), Use(\"material\"), Use(\"shadow\")],",
    );
    let err = render_graph_fails(&path);
    assert!(err.contains("unknown resource 'film'"), "{err}");
    assert!(
        err.contains("passes/pt.ron:"),
        "the error points into the catalog that names it: {err}"
    );
}

#[test]
fn stream_type_mismatch() {
    let (text, path) = pt_variant(
        "stream-mismatch",
        "\"shadow\": (item: \"ShadowRay\"",
        "\"shadow\": (item: \"CameraPath\"",
    );
    let err = render_graph_fails(&path);
    assert!(
        err.contains("stream type mismatch") && err.contains("'CameraPath'") && err.contains("'ShadowRay'"),
        "{err}"
    );
    assert_at_line(&err, "stream-mismatch.ron", &text, "\"shadow\": (item");
}

#[test]
fn unknown_layout_lists_the_available_ones() {
    let err = fails(&["render", "--layout", "FastestPT", "--res", "8x8", "--frames", "1"]);
    assert!(
        err.contains("unknown layout 'FastestPT'") && err.contains("NaivePTsk") && err.contains("NaivePTmk"),
        "{err}"
    );
}

#[test]
fn a_constant_out_of_its_range_is_refused_at_its_check() {
    // Without the check, PM_STRUCTURE 4 culled every structure and with them the photons.
    let out = temp_dir("range").join("range.exr");
    let err = fails(&[
        "render",
        "--graph",
        "ppm",
        "--set",
        "PM_STRUCTURE=4",
        "--res",
        "8x8",
        "--frames",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let catalog = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/passes/pm.ron")).unwrap();
    let at = format!("passes/pm.ron:{}:", line_of(&catalog, "\"PM_STRUCTURE <= 3\""));
    assert!(
        err.contains(&at) && err.contains("(PM_STRUCTURE = 4)") && err.contains("3 (kD-tree)"),
        "{err}"
    );
}

#[test]
fn missing_scene_file() {
    let err = fails(&["render", "--scene", "/no/such/scene.ron", "--frames", "1"]);
    assert!(
        err.contains("/no/such/scene.ron") && err.contains("not found") && err.contains("cornell-diffuse"),
        "{err}"
    );
}

#[test]
fn scene_without_light() {
    let path = data("scenes/no-light.ron");
    let err = fails(&["render", "--scene", path.to_str().unwrap(), "--frames", "1"]);
    assert!(err.contains("no-light.ron") && err.contains("no light"), "{err}");
}

#[test]
fn malformed_scene_names_line_and_column() {
    let path = temp_dir("bad-scene").join("bad.ron");
    std::fs::write(&path, "Scene(\n    camera: (position: (0.0, 0.0), look: Target((0.0, 0.0, 1.0)), up: (0.0, 1.0, 0.0), fov_degrees: 40.0),\n)").unwrap();
    let err = fails(&["render", "--scene", path.to_str().unwrap(), "--frames", "1"]);
    assert!(err.contains("bad.ron:2:"), "{err}");
}

#[test]
fn ambient_occlusion_renders_through_the_cli() {
    let dir = temp_dir("ao");
    let exr = dir.join("ao.exr");
    let out = lightgraph(&[
        "render",
        "--graph",
        "ao",
        "--scene",
        "cornell-diffuse",
        "--res",
        "16x16",
        "--frames",
        "2",
        "--out",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(exr.is_file());
}

#[test]
fn fusing_across_a_barrier_names_both_passes_and_the_resource() {
    let (text, path) = pt_variant(
        "barrier",
        "\"NaivePTsk\": (",
        "\"Fused\": (kernels: [[\"generate\", \"trace\", \"logic\", \"material\", \"shadow\", \"accumulate\"]]),\n        \"NaivePTsk\": (",
    );
    let err = fails(&[
        "render",
        "--graph",
        path.to_str().unwrap(),
        "--layout",
        "Fused",
        "--res",
        "8x8",
        "--frames",
        "1",
    ]);
    assert!(
        err.contains("'generate'") && err.contains("'accumulate'") && err.contains("'film'") && err.contains("barrier"),
        "{err}"
    );
    assert_at_line(&err, "barrier.ron", &text, "\"accumulate\"]]");
}

#[test]
fn a_layout_naming_an_unknown_pass_or_option_is_refused() {
    let (_, path) = pt_variant(
        "layout-pass",
        "\"NaivePTsk\": (",
        "\"Odd\": (kernels: [[\"generate\", \"trace\", \"logic\", \"material\", \"shade\"], [\"shadow\"], [\"accumulate\"]]),\n        \"NaivePTsk\": (",
    );
    let err = fails(&[
        "render",
        "--graph",
        path.to_str().unwrap(),
        "--layout",
        "Odd",
        "--res",
        "8x8",
        "--frames",
        "1",
    ]);
    assert!(err.contains("unknown pass 'shade'") && err.contains("'Odd'"), "{err}");
    let (text, path) = pt_variant(
        "layout-option",
        "            like: \"RegenerationPTmk2\",\n            policy: Compaction,",
        "            like: \"RegenerationPTmk2\",\n            polcy: Compaction,",
    );
    let err = render_graph_fails(&path);
    assert!(err.contains("polcy"), "{err}");
    assert_at_line(&err, "layout-option.ron", &text, "polcy");
}
