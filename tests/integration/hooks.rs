//! Hooks and item fields (docs/graphs.md, "Hooks and item fields"): a graph that extends
//! progressive photon mapping to store caustic photons only, through the hook
//! `pm_stores_photon` and a field it adds to the light sub-path (tests/data/graphs/
//! ppm-caustic.ron, no function copied), rendered fused and split, beside maps of no photons
//! and camera vertices that merge none (the hook `pm_merges_photon`); and the errors of hooks
//! and fields that do not fit, each at its file and line.

use crate::bpt::sds_scene;
use crate::common::{data, kernel_sources, render_with_layout};
use lightgraph::run::{Image, LayoutOverrides, LoadedScene, load_scene};
use lightgraph_engine::ir::StateStorage;
use lightgraph_engine::{ConstValue, Graph, Layer};
use std::path::PathBuf;

/// A test graph of tests/data/graphs, as a path the CLI takes.
fn test_graph(name: &str) -> String {
    data(&format!("graphs/{name}.ron")).to_string_lossy().to_string()
}

/// `graph` on `scene` in `layout` with item state `state`: 16x16 pixels, 4 samples per pixel,
/// 2 frames, seed 7.
fn image(scene: &LoadedScene, graph: &str, layout: &str, state: StateStorage) -> Image {
    let overrides = LayoutOverrides {
        state: Some(state),
        ..Default::default()
    };
    render_with_layout(scene, graph, layout, (16, 16), 4, 2, 7, &[], overrides).image
}

/// The mean of the image's pixels over the channels.
fn mean(image: &Image) -> f64 {
    let sum: f64 = image.mean.iter().flat_map(|p| p[..3].iter()).map(|v| *v as f64).sum();
    sum / (3 * image.mean.len()) as f64
}

#[test]
fn a_caustic_photon_map_is_a_hook_and_an_added_field() {
    let diffuse = load_scene("cornell-diffuse").unwrap();
    let glass = sds_scene();
    let (caustic, none) = (test_graph("ppm-caustic"), test_graph("ppm-no-photons"));
    // PPMsk keeps the light sub-path in registers; PPMmk stores it between kernels and loop
    // iterations (compacted), where `met_rough` must be packed to be read at the next vertex.
    for (layout, state) in [
        ("PPMsk", StateStorage::SoA),
        ("PPMmk", StateStorage::SoA),
        ("PPMmk", StateStorage::AoS),
    ] {
        let what = format!("{layout} ({state:?})");
        // A box of diffuse walls has no caustic: the caustic map renders what no photons do
        // (the light seen directly), bit for bit, where the global map lights the walls.
        let c = image(&diffuse, &caustic, layout, state);
        let n = image(&diffuse, &none, layout, state);
        let global = image(&diffuse, "ppm", layout, state);
        assert_eq!(c.mean, n.mean, "{what}: a caustic photon on a diffuse box");
        // Camera vertices that merge nothing they find render the same.
        let m = image(&diffuse, &test_graph("ppm-merges-nothing"), layout, state);
        assert_eq!(m.mean, n.mean, "{what}: a photon merged where the hook merges none");
        assert!(
            mean(&global) > 1.5 * mean(&n),
            "{what}: global {} vs none {}",
            mean(&global),
            mean(&n)
        );
        // A point light in a glass ball lights the floor through the glass alone: caustics.
        let (c, n, global) = (
            image(&glass, &caustic, layout, state),
            image(&glass, &none, layout, state),
            image(&glass, "ppm", layout, state),
        );
        eprintln!(
            "{what}: glass ball: caustic {}, none {}, global {}",
            mean(&c),
            mean(&n),
            mean(&global)
        );
        assert!(
            mean(&c) > 0.5 * mean(&global) && mean(&c) > 10.0 * mean(&n) + 1e-6,
            "{what}: caustics"
        );
        assert!(
            mean(&c) <= mean(&global) * 1.001,
            "{what}: more caustic than global light"
        );
    }
}

#[test]
fn an_added_field_is_loaded_and_stored_in_split_kernels() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let constants = [("PM_AVERAGE_LENGTH", ConstValue::F32(1.0))];
    let text = kernel_sources(&test_graph("ppm-caustic"), "PPMmk", &scene, &constants, false);
    assert!(
        text.contains("v.met_rough = bitcast<u32>(") && text.contains("bitcast<u32>(v.met_rough)"),
        "the added field is neither loaded nor stored between PPMmk's kernels"
    );
}

/// A folder of its own for `files` (path, text) of a test.
fn folder(test: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-hooks-{}-{test}", std::process::id()));
    for (path, text) in files {
        let full = dir.join(path);
        std::fs::create_dir_all(full.parent().unwrap()).unwrap();
        std::fs::write(full, text).unwrap();
    }
    dir
}

/// The error of loading `g.ron` (`graph`) beside `files`.
fn load_error(test: &str, graph: &str, files: &[(&str, &str)]) -> String {
    let mut all = vec![("g.ron", graph)];
    all.extend_from_slice(files);
    let dir = folder(test, &all);
    let vfs = lightgraph::assets::builtin().with_front(Layer::Dir(dir.clone()));
    let err = Graph::load(&vfs, "g.ron").map(|_| ()).unwrap_err().to_string();
    std::fs::remove_dir_all(dir).unwrap();
    err
}

/// The 1-based line of `text` that holds `needle` first.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("the needle is in the text")
        + 1
}

/// A graph extending ppm with `fields` (RON) for its `item_fields` and `hooks` for its hooks.
fn extending(fields: &str, hooks: &str) -> String {
    format!("(\n    extends: \"graphs/ppm.ron\",\n    item_fields: {{{fields}}},\n    hooks: {{{hooks}}},\n)\n")
}

const STORES_BY_LENGTH: &str =
    "fn pm_stores_photon(p: ptr<function, PhotonPath>) -> bool {\n    return (*p).light.length > 1u;\n}\n";

#[test]
fn hooks_that_do_not_fit_are_errors_at_their_file_and_line() {
    let g = extending("", "\n        \"pm_stores_photons\": \"my.wgsl\",\n    ");
    let err = load_error("unknown", &g, &[("my.wgsl", STORES_BY_LENGTH)]);
    let at = format!("g.ron:{}:", line_of(&g, "pm_stores_photons"));
    assert!(err.starts_with(&at), "{err}");
    assert!(
        err.contains("no hook 'pm_stores_photons'") && err.contains("its hooks: "),
        "{err}"
    );
    assert!(
        err.matches("pm_stores_photon").count() >= 2,
        "the hooks are listed: {err}"
    );

    let g = extending("", "\n        \"pm_stores_photon\": \"my.wgsl\",\n    ");
    let text = format!("// Stores where the sub-path is long.\n{STORES_BY_LENGTH}");
    let err = load_error("signature", &g, &[("my.wgsl", &text)]);
    assert!(err.starts_with("my.wgsl:2:4:"), "{err}");
    assert!(
        err.contains("takes (ptr<function, PhotonPath>) and returns bool")
            && err.contains(
                "`fn pm_stores_photon(p: ptr<function, PhotonPath>, a: Arrival) -> bool` (shaders/pm/light.wgsl:"
            ),
        "{err}"
    );

    let err = load_error(
        "missing",
        &g,
        &[("my.wgsl", "fn pm_store_photon() -> bool { return true; }\n")],
    );
    let at = format!("g.ron:{}:", line_of(&g, "pm_stores_photon"));
    assert!(
        err.starts_with(&at) && err.contains("my.wgsl defines no function 'pm_stores_photon'"),
        "{err}"
    );
}

#[test]
fn item_fields_that_do_not_fit_are_errors_at_their_line() {
    for (fields, needle, message) in [
        (
            "\n        \"Photon\": [(\"caustic\", \"u32\")],\n    ",
            "\"Photon\"",
            "'Photon' is no item of this graph",
        ),
        (
            "\n        \"PhotonPath\": [(\"alive\", \"u32\")],\n    ",
            "alive",
            "'PhotonPath' already has a field 'alive'",
        ),
        (
            "\n        \"PhotonPath\": [\n            (\"seen\", \"u32\"),\n            (\"seen\", \"f32\"),\n        ],\n    ",
            "seen",
            "'PhotonPath' already has a field 'seen'",
        ),
        (
            "\n        \"PhotonPath\": [(\"caustic\", \"bool\")],\n    ",
            "caustic",
            "a bool cannot be stored between kernels",
        ),
    ] {
        let g = extending(fields, "");
        let err = load_error("fields", &g, &[]);
        let at = format!("g.ron:{}:", line_of(&g, needle));
        assert!(err.starts_with(&at) && err.contains(message), "{fields}: {err}");
    }
}

#[test]
fn the_graph_guide_shows_the_caustic_example_as_tested() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/graphs.md")).unwrap();
    let section = &doc[doc.find("## Hooks and item fields").expect("the section")..];
    for file in ["graphs/ppm-caustic.ron", "graphs/shaders/caustic_photons.wgsl"] {
        let text = std::fs::read_to_string(data(file)).unwrap();
        assert!(
            section.contains(&format!("\n{text}```")),
            "docs/graphs.md shows tests/data/{file} as it is"
        );
    }
}
