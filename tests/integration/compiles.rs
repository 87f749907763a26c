//! One compile a render (issue 41): `render` compiles its graph once (the engine's one compile
//! entry, counted on the calling thread), a graph with measured constants once more for each
//! measurement, and `--layout auto` once for each layout it measures.

use lightgraph::run::{AUTO_LAYOUT, Run, RunSpec};
use lightgraph::tune::Trial;
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

/// `render --layout auto` of `graph` on a small diffuse box as the render does it: the tuning
/// ([`lightgraph::tune::tune`], which makes the winner the run's layout), the measured
/// constants ([`Run::measure`]) and the render's session ([`Run::session`]); the programs
/// these compile, the trials and the run.
fn tuned_render(graph: &str) -> (u64, Vec<Trial>, Run) {
    let spec = RunSpec {
        scene: "cornell-diffuse".into(),
        graph: graph.into(),
        layout: Some(AUTO_LAYOUT.into()),
        res: Some((16, 16)),
        ..RunSpec::default()
    };
    let gpu = crate::common::gpu();
    let mut run = Run::load(&spec).unwrap();
    let before = compiles_on_this_thread();
    let budget = std::time::Duration::from_millis(5);
    let trials = lightgraph::tune::tune(gpu, &mut run, budget, |_| ()).unwrap();
    assert_eq!(run.layout, trials[0].name, "the winner is the run's layout");
    run.measure(gpu).unwrap();
    assert!(run.measured());
    run.session(gpu).unwrap();
    (compiles_on_this_thread() - before, trials, run)
}

#[test]
fn layout_auto_compiles_each_layout_it_measures_once() {
    let (compiles, trials, mut run) = tuned_render("ao");
    assert!(trials.len() > 1);
    assert_eq!(
        compiles,
        trials.len() as u64,
        "the render takes the program its winner's trial compiled"
    );
    // Another layout is compiled, not given the winner's program.
    let gpu = crate::common::gpu();
    let default = run.graph.default_layout.clone();
    run.relayout(&default).unwrap();
    let before = compiles_on_this_thread();
    run.session(gpu).unwrap();
    assert_eq!(compiles_on_this_thread() - before, 1);
}

/// The winner of a graph with a measured constant: its trial measured the constant and
/// compiled with it, and the render takes both (no compile more), rendering the image of its
/// layout measured and compiled anew.
#[test]
fn a_tuned_layout_brings_its_measured_constant() {
    let gpu = crate::common::gpu();
    let spec = RunSpec {
        scene: "cornell-diffuse".into(),
        graph: "ppm".into(),
        res: Some((16, 16)),
        ..RunSpec::default()
    };
    let mut run = Run::load(&spec).unwrap();
    assert_eq!(run.graph.measured.len(), 1);
    let (layout, decl) = ("PPMmk".to_string(), run.graph.layout("PPMmk").unwrap().clone());
    let before = compiles_on_this_thread();
    let trial = run.session_in(gpu, &layout, &decl).unwrap();
    assert_eq!(compiles_on_this_thread() - before, 2, "a trial measures and compiles");
    run.take_tuned(gpu, (layout.clone(), decl.clone()), Some(trial.program().clone()));
    assert!(run.measured(), "the trial's measurement is the run's");
    let before = compiles_on_this_thread();
    run.measure(gpu).unwrap();
    let mut tuned = run.session(gpu).unwrap();
    assert_eq!(compiles_on_this_thread() - before, 0);

    let mut again = Run::load(&spec).unwrap();
    again.take_tuned(gpu, (layout, decl), None);
    again.measure(gpu).unwrap();
    assert_eq!(again.options, run.options, "the same measured constant");
    let mut fresh = again.session(gpu).unwrap();
    for session in [&mut tuned, &mut fresh] {
        session.render_frames(2).unwrap();
    }
    assert_eq!(tuned.image().unwrap().mean, fresh.image().unwrap().mean);
}
