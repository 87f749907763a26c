//! Hooks and item fields (docs/graphs.md, "Hooks and item fields"): a graph that extends
//! progressive photon mapping to store caustic photons only, through the hook
//! `pm_stores_photon` and a field it adds to the light sub-path (tests/data/graphs/
//! ppm-caustic.ron, no function copied), rendered fused and split, beside maps of no photons
//! and camera vertices that merge none (the hook `pm_merges_photon`); VCM's merges that take
//! no cached vertex (`vcm_merges_vertex`), another random-number source (`rng_u32`) and
//! another Markov chain evaluator (`mlt_path`); and the errors of hooks and fields that do not
//! fit, each at its file and line.

use crate::bpt::sds_scene;
use crate::common::{
    borrowed, data, gpu, kernel_sources, largest_relative_difference, measured, options, render, render_with_layout,
};
use lightgraph::run::{Image, LayoutOverrides, LoadedScene, Session, load_graph, load_scene};
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

/// The standard error of [`mean`], from the pixels' variances over the frames: the pixels
/// independent, a pixel's three channels taken as fully correlated (an upper bound).
fn standard_error(image: &Image) -> f64 {
    let sum: f64 = image
        .variance
        .iter()
        .map(|p| (p.iter().map(|v| (*v as f64).sqrt()).sum::<f64>() / 3.0).powi(2))
        .sum();
    (sum / image.frames as f64).sqrt() / image.variance.len() as f64
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

/// The per-pixel sums (RGB) of `graph`'s estimates in `layout` with `constants`, and of its
/// biased channel's (VCM's merges' light): the diffuse box at 16x16, 2 samples per pixel, 2
/// frames, seed 44.
fn sums_and_merges(graph: &str, layout: &str, constants: &[(&str, ConstValue)]) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let scene = load_scene("cornell-diffuse").unwrap();
    let loaded = load_graph(graph).unwrap();
    let opts = options((16, 16), 2, 44, constants, Default::default());
    let mut session = Session::new(gpu(), &loaded, layout, &scene, opts).unwrap();
    for _ in 0..2 {
        session.render_frame().unwrap();
    }
    let all = session.take_accumulation().unwrap();
    let merges = session
        .take_biased()
        .unwrap()
        .expect("VCM adds its merges to a biased channel");
    let rgb = |s: &[f32; 4]| [0, 1, 2].map(|c| s[c] as f64);
    (all.sum.iter().map(rgb).collect(), merges.iter().map(rgb).collect())
}

#[test]
fn a_vcm_merge_that_takes_no_vertex_loses_the_merges_light_alone() {
    let scene = load_scene("cornell-diffuse").unwrap();
    for layout in ["VCMsk", "VCMmk"] {
        // A radius at which merges find vertices at most pixels, and one measurement of the
        // graph's constants for both runs (see `measured`).
        let radius = ("PM_RADIUS", ConstValue::F32(0.05));
        let owned = measured(&scene, "vcm", layout, ((16, 16), 2, 44), &[radius]);
        let mut constants = borrowed(&owned);
        constants.push(radius);
        let (all, merges) = sums_and_merges("vcm", layout, &constants);
        let (rest, none) = sums_and_merges(&test_graph("vcm-merges-nothing"), layout, &constants);
        assert!(
            none.iter().all(|p| *p == [0.0; 3]),
            "{layout}: a merge took a vertex the hook declines"
        );
        let merged = merges.iter().filter(|p| p.iter().any(|v| *v > 0.0)).count();
        assert!(merged > merges.len() / 2, "{layout}: VCM's merges lit {merged} pixels");
        // Everything else is the same paths with the same weights: each pixel is VCM's less
        // its merges' light, to the rounding of the sums and of the splats' atomic order.
        for (i, ((a, r), m)) in all.iter().zip(&rest).zip(&merges).enumerate() {
            for c in 0..3 {
                let expected = a[c] - m[c];
                assert!(
                    (r[c] - expected).abs() <= 1e-4 * a[c].abs().max(1e-2),
                    "{layout}: pixel {i} channel {c}: {} without merges, VCM {} less its merges {}",
                    r[c],
                    a[c],
                    m[c]
                );
            }
        }
    }
}

#[test]
fn another_random_number_source_renders_the_same_estimate_from_other_numbers() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let pcg = render(&scene, "pt", "NaivePTsk", (16, 16), 4, 8, 7, &[]).image;
    let xorshift = render(&scene, &test_graph("pt-xorshift"), "NaivePTsk", (16, 16), 4, 8, 7, &[]).image;
    let differs = largest_relative_difference(&pcg, &xorshift);
    assert!(differs > 0.1, "the replaced rng_u32 drew the PCG's numbers: {differs}");
    // The two image means agree within four standard errors.
    let (a, b) = (mean(&pcg), mean(&xorshift));
    let se = (standard_error(&pcg).powi(2) + standard_error(&xorshift).powi(2)).sqrt();
    assert!(
        (a - b).abs() < 4.0 * se,
        "PCG mean {a}, xorshift mean {b}, standard error {se}"
    );
}

#[test]
fn a_replaced_chain_evaluator_is_the_one_the_chains_run() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let image = render(
        &scene,
        &test_graph("pssmlt-first-pixel"),
        "PSSMLTsk",
        (16, 16),
        1,
        2,
        7,
        &[],
    )
    .image;
    // Pixel 0 of the film, whichever corner of the image it is.
    let lit: Vec<&[f32; 3]> = image.mean.iter().filter(|p| **p != [0.0; 3]).collect();
    assert_eq!(lit.len(), 1, "the chains' splats went to {} pixels", lit.len());
    assert!(lit[0].iter().all(|v| *v > 0.0), "{:?}", lit[0]);
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
    extending_graph("ppm", fields, hooks)
}

/// A graph extending the built-in `base` with `fields` (RON) for its `item_fields` and `hooks`
/// for its hooks.
fn extending_graph(base: &str, fields: &str, hooks: &str) -> String {
    format!("(\n    extends: \"graphs/{base}.ron\",\n    item_fields: {{{fields}}},\n    hooks: {{{hooks}}},\n)\n")
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
fn replacements_of_other_signatures_are_errors_at_their_fn() {
    for (base, hook, text, takes, expected) in [
        (
            "pssmlt",
            "mlt_path",
            "// The light only.\nfn mlt_path(src: ptr<function, PrimarySamples>) -> vec3<f32> {\n    return vec3<f32>(1.0);\n}\n",
            "takes (ptr<function, PrimarySamples>) and returns vec3<f32>",
            "`fn mlt_path(src: ptr<function, PrimarySamples>) -> MltPath` (shaders/mlt/path.wgsl:",
        ),
        (
            "pt",
            "rng_u32",
            "// A counter.\nfn rng_u32(state: u32) -> u32 {\n    return state + 1u;\n}\n",
            "takes (u32) and returns u32",
            "`fn rng_u32(state: ptr<function, u32>) -> u32` (shaders/lib/rng.wgsl:",
        ),
        (
            "vcm",
            "vcm_merges_vertex",
            "// Takes a photon.\nfn vcm_merges_vertex(m: Merge, photon: Photon) -> bool {\n    return true;\n}\n",
            "takes (Merge, Photon) and returns bool",
            "`fn vcm_merges_vertex(m: Merge, v: LightVertex) -> bool` (shaders/vcm/vcm.wgsl:",
        ),
    ] {
        let g = extending_graph(base, "", &format!("\n        \"{hook}\": \"my.wgsl\",\n    "));
        let err = load_error(&format!("signature-{hook}"), &g, &[("my.wgsl", text)]);
        assert!(err.starts_with("my.wgsl:2:4:"), "{hook}: {err}");
        assert!(err.contains(takes) && err.contains(expected), "{hook}: {err}");
    }
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
