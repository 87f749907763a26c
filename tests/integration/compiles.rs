//! One compile a render (issue 41): `render` compiles its graph once (the engine's one compile
//! entry, counted on the calling thread), a graph with measured constants once more for each
//! measurement, and `--layout auto` once for each layout it measures.

use lightgraph::run::{Run, RunSpec};
use lightgraph_engine::compiles_on_this_thread;

/// The programs `lightgraph ARGS` compiles, run in this thread.
fn compiles_of(args: &[&str]) -> u64 {
    let before = compiles_on_this_thread();
    let argv = std::iter::once("lightgraph").chain(args.iter().copied());
    lightgraph::cli::Cli::parse_from_args(argv).unwrap().run().unwrap();
    compiles_on_this_thread() - before
}

/// `render` of `graph` in `layout` on a small diffuse box into a folder of its own.
fn render(graph: &str, layout: &str) -> u64 {
    let out = crate::cli::temp_dir("compiles").join(format!("{graph}-{layout}.exr"));
    let out = out.to_str().unwrap();
    let scene = ["--scene", "cornell-diffuse", "--res", "16x16", "--frames", "2"];
    let run = ["--graph", graph, "--layout", layout, "--out", out, "--force"];
    compiles_of(&["render"].into_iter().chain(scene).chain(run).collect::<Vec<_>>())
}

#[test]
fn a_render_compiles_its_graph_once() {
    assert_eq!(render("pt", "NaivePTsk"), 1);
    assert_eq!(render("pt", "WavefrontPT"), 1);
}

#[test]
fn a_measured_constant_costs_one_compile_more() {
    for (graph, layout) in [("bpt-lvc", "LVC-BPTsk"), ("ppm", "PPMmk")] {
        assert_eq!(lightgraph::run::load_graph(graph).unwrap().measured.len(), 1);
        assert_eq!(render(graph, layout), 2, "{graph}");
    }
}

#[test]
fn layout_auto_compiles_each_layout_it_measures_once() {
    let spec = RunSpec {
        scene: "cornell-diffuse".into(),
        graph: "ao".into(),
        res: Some((16, 16)),
        ..RunSpec::default()
    };
    let run = Run::load(&spec).unwrap();
    let before = compiles_on_this_thread();
    let budget = std::time::Duration::from_millis(5);
    let trials = lightgraph::tune::autotune(crate::common::gpu(), &run, budget, |_| ()).unwrap();
    assert!(trials.len() > 1);
    assert_eq!(compiles_on_this_thread() - before, trials.len() as u64);
}
