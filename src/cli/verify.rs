//! `lightgraph verify`: every estimator against every other on a list of scenes, with the
//! films' own noise; the report says which pairs agree, which differ (and where), and which
//! the budget cannot decide (src/verify, docs/verify.md).

use super::args::*;
use super::checks::constant_names;
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::compare::EstimatorSpec;
use lightgraph::output::{Output, check_outputs, write_exr, write_png};
use lightgraph::run::{LoadedScene, Run as Loaded, Scenes, load_graph, named_layout, parse_sets};
use lightgraph::study::scene_folders;
use lightgraph::verify::batches::{Amount, RunBatches, render_batches};
use lightgraph::verify::paths::{Kinds, describe, scene_kinds};
use lightgraph::verify::preset::{Given, Power, Preset};
use lightgraph::verify::report::{RunLine, SceneImages, html_path, map_name, write_html, write_map, write_tables};
use lightgraph::verify::stats::{Biased, TestSettings, compare};
use lightgraph::verify::{
    Claims, DEFAULT_ESTIMATORS, DEFAULT_SCENES, Outcome, PairResult, claims, expected_gaps, run_constants,
    unconfirmed_gaps,
};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{Gpu, Graph};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// The arguments of `lightgraph verify`.
#[derive(Args)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub common: Common,
    /// Scenes, comma-separated: built-in names or scene files.
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_SCENES)]
    pub scenes: Vec<String>,
    /// Estimators, comma-separated `graph[:Layout][@NAME=VALUE...]`: built-in graphs or your
    /// own graph files [default: every built-in graph of radiance, and VCM's two halves alone].
    #[arg(long)]
    pub graphs: Option<String>,
    /// Estimators verified besides those of --graphs (or the default set), e.g. your own
    /// graph file.
    #[arg(long)]
    pub add: Option<String>,
    /// Budget and power settings by name (--res, --spp, --time or --frames, --batches,
    /// --block, --detect-mean, --detect-block, --coverage); each of those options given
    /// explicitly wins over its preset's value.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Rendering time of each estimator on each scene (set-up off the clock) [default: 10s].
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, conflicts_with = "frames")]
    pub time: Option<Duration>,
    /// Frames of each estimator on each scene instead of a time (reproducible).
    #[arg(long, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Batches each run is split into: the samples of the standard errors [default: 16].
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..))]
    pub batches: Option<u32>,
    /// Side of the blocks compared, in pixels [default: 16].
    #[arg(long, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub block: Option<u32>,
    /// Family-wise error of the run: the chance that any pair of estimators that agree is
    /// called different (each pair is tested at alpha over the number of pairs).
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// The probability with which the test must see the differences below.
    #[arg(long, default_value_t = 0.9)]
    pub power: f64,
    /// Relative difference of the image means the test must see for "agree" [default: 0.01].
    #[arg(long)]
    pub detect_mean: Option<f64>,
    /// Relative difference of a block the test must see for "agree" ... [default: 0.1]
    #[arg(long)]
    pub detect_block: Option<f64>,
    /// ... in the blocks holding this fraction of the image's light [default: 0.9].
    #[arg(long)]
    pub coverage: Option<f64>,
    /// The bias an estimator may have in the image mean, as a fraction of the light of the
    /// path classes its graph declares biased at a finite budget (photon mapping's and VCM's
    /// merges, which blur by a radius that shrinks): that difference is allowed on top of the
    /// noise.
    #[arg(long, default_value_t = 0.01)]
    pub bias_tolerance_mean: f64,
    /// The same for a block's mean.
    #[arg(long, default_value_t = 0.1)]
    pub bias_tolerance_block: f64,
    /// Fail when a declared gap shows in no pair of the run (a declaration that claims more
    /// than its graph misses). Only for scene lists where every declared gap carries light
    /// (the default boxes do), so it is off by default: a graph verified on one scene should
    /// not fail for another graph's gap that scene does not show.
    #[arg(long)]
    pub check_gaps: bool,
    /// Seed of the runs' random streams (each estimator's its own from it).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Output folder: verify.md, verify.csv, and per scene each run's EXR and PNG and a map of
    /// every pair that differs.
    #[arg(long, default_value = "out/verify")]
    pub out: PathBuf,
    /// Write into a --out that holds an earlier run's verify.md, verify.csv, report.html and
    /// images, replacing them.
    #[arg(long)]
    pub force: bool,
    /// Exposure of the PNG previews in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

impl VerifyArgs {
    /// The budget and power settings: those given, else the preset's, else the defaults.
    fn power_settings(&self) -> Power {
        let given = Given {
            res: self.common.res,
            spp: self.common.spp,
            amount: match (self.frames, self.time) {
                (Some(n), _) => Some(Amount::Frames(n)),
                (None, time) => time.map(Amount::Time),
            },
            batches: self.batches,
            block: self.block,
            detect_mean: self.detect_mean,
            detect_block: self.detect_block,
            coverage: self.coverage,
        };
        given.resolve(self.preset)
    }

    fn settings(&self) -> Result<TestSettings> {
        let unit = |name: &str, v: f64| {
            if !(v > 0.0 && v < 1.0) {
                bail!("--{name} {v}: must lie between 0 and 1");
            }
            Ok(v)
        };
        let tolerance = |name: &str, v: f64| {
            if !(0.0..1.0).contains(&v) {
                bail!("--{name} {v}: must be at least 0 and below 1");
            }
            Ok(v)
        };
        let power = self.power_settings();
        Ok(TestSettings {
            alpha: unit("alpha", self.alpha)?,
            pairs: 1,
            power: unit("power", self.power)?,
            detect_mean: unit("detect-mean", power.detect_mean)?,
            detect_block: unit("detect-block", power.detect_block)?,
            coverage: unit("coverage", power.coverage)?,
            bias_tolerance_mean: tolerance("bias-tolerance-mean", self.bias_tolerance_mean)?,
            bias_tolerance_block: tolerance("bias-tolerance-block", self.bias_tolerance_block)?,
        })
    }
}

/// One estimator: its label, graph and layout, and its own constant settings.
struct Estimator {
    label: String,
    spec: EstimatorSpec,
    graph: Graph,
    layout: String,
}

/// One estimator's run on a scene, with its claims under the run's constants.
struct Run {
    label: String,
    claims: Claims,
    result: RunBatches,
}

impl Run {
    /// What of its estimate its graph declares biased on a scene whose paths have `kinds`:
    /// nothing where no declared class has paths there that it samples, else the light of its
    /// film's biased channel where it has one, else all of it.
    fn biased(&self, kinds: Kinds) -> Biased {
        match (self.claims.biased_with(kinds), &self.result.biased) {
            (false, _) => Biased::None,
            (true, Some(part)) => Biased::Part(part.estimates()),
            (true, None) => Biased::All,
        }
    }
}

/// Runs `verify`: every estimator on every scene, the pairs compared, the reports written; an
/// error when a pair is not as predicted or cannot be decided.
pub fn verify(args: VerifyArgs) -> Result<()> {
    if let Some(scene) = &args.common.scene {
        bail!("verify renders the scenes of --scenes, not --scene {scene}: name it there");
    }
    let mut settings = args.settings()?;
    let power = args.power_settings();
    let estimators = estimators(&args)?;
    settings.pairs = args.scenes.len() * pairs_of(&estimators)?;
    for scene in &args.scenes {
        find_scene(scene, "--scenes")?;
    }
    let folders = scene_folders(&args.scenes)?;
    check_outputs(
        &[Output::Folder(&args.out, &["verify.md", "verify.csv", "report.html"])],
        args.force,
        None,
    )?;
    let gpu = Gpu::new(args.common.adapter.as_deref())?;
    eprintln!(
        "{} | {} estimators on {} scenes, {} each in {} batches",
        gpu.describe(),
        estimators.len(),
        args.scenes.len(),
        match power.amount {
            Amount::Frames(n) => format!("{n} frames"),
            Amount::Time(t) => format!("{t:?}"),
        },
        power.batches
    );
    let (mut lines, mut pairs, mut images) = (Vec::new(), Vec::new(), Vec::new());
    let mut md = String::new();
    for (scene, folder) in args.scenes.iter().zip(&folders) {
        let (scene_lines, scene_pairs, scene_images) =
            verify_scene(&args, &settings, &gpu, (scene, folder), &estimators)
                .with_context(|| format!("scene {scene}"))?;
        lines.extend(scene_lines);
        pairs.extend(scene_pairs);
        images.push(scene_images);
        // After every scene, so that a run stopped early keeps what it found.
        md = write_tables(&args.out, &settings, &lines, &pairs)?;
        write_html(&args.out, &md, &images, &pairs, power.block)?;
    }
    println!(
        "{md}\nwrote {0}/verify.md, verify.csv, {1} (opens offline in a browser) and per scene each run's EXR and PNG",
        args.out.display(),
        html_path(&args.out).display()
    );
    let count = |o: Outcome| pairs.iter().filter(|p| p.outcome == o).count();
    let (unexpected, undecided) = (count(Outcome::UnexpectedDifference), count(Outcome::Undecided));
    let unconfirmed = match args.check_gaps {
        true => unconfirmed_gaps(&pairs),
        false => Vec::new(),
    };
    if unexpected > 0 || !unconfirmed.is_empty() {
        bail!(
            "{unexpected} pairs differ where nothing declared says they may, and {} declared gaps showed in no pair \
             (see {})",
            unconfirmed.len(),
            args.out.join("verify.md").display()
        );
    }
    if undecided > 0 {
        bail!("{undecided} pairs could not be decided at this budget: give more --time or --frames");
    }
    Ok(())
}

/// The pairs of estimators of the same quantity, which a scene compares.
fn pairs_of(estimators: &[Estimator]) -> Result<usize> {
    let mut per_quantity = std::collections::BTreeMap::<String, usize>::new();
    for e in estimators {
        *per_quantity
            .entry(claims(&e.graph, &Default::default())?.estimates)
            .or_default() += 1;
    }
    Ok(per_quantity.values().map(|n| n * n.saturating_sub(1) / 2).sum())
}

/// The estimators of `--graphs` (or the default set) and `--add`, loaded and checked before
/// anything renders.
fn estimators(args: &VerifyArgs) -> Result<Vec<Estimator>> {
    let mut list = args.graphs.clone().unwrap_or_else(|| DEFAULT_ESTIMATORS.to_string());
    if let Some(add) = &args.add {
        list = format!("{list},{add}");
    }
    let mut out = Vec::new();
    for spec in estimator_specs(&list, "--graphs")? {
        let graph = load_graph(&spec.graph)?;
        let (layout, _) = named_layout(&graph, spec.layout.as_deref())?;
        // The claims are checked now, so that a malformed one costs no rendering.
        claims(&graph, &Default::default())?;
        let mut label = graph.name.clone();
        if let Some(layout) = &spec.layout {
            label += &format!(":{layout}");
        }
        for set in &spec.sets {
            label += &format!("@{set}");
        }
        out.push(Estimator {
            label,
            spec,
            graph,
            layout,
        });
    }
    check_sets(&args.common.set, &out)?;
    Ok(out)
}

/// Checks that every `--set NAME=VALUE` names a constant of at least one estimator's graph
/// (each takes its own, `own_sets`), with a value of its type: a mistyped name is an error,
/// not a setting no graph reads.
fn check_sets(sets: &[String], estimators: &[Estimator]) -> Result<()> {
    for e in estimators {
        parse_sets(&own_sets(sets, &e.graph), &e.graph, "--set ")?;
    }
    for set in sets {
        let name = set.split_once('=').map_or(set.as_str(), |(name, _)| name.trim());
        if !estimators.iter().any(|e| constant_names(&e.graph).contains(&name)) {
            let graphs: Vec<&str> = estimators.iter().map(|e| e.graph.name.as_str()).collect();
            bail!(
                "--set {set}: no graph of the run ({}) has a constant {name}",
                graphs.join(", ")
            );
        }
    }
    Ok(())
}

/// Renders every estimator on one scene and compares every pair of the same quantity;
/// returns the runs' lines, the pairs and the runs' images.
fn verify_scene(
    args: &VerifyArgs,
    settings: &TestSettings,
    gpu: &Gpu,
    (scene, folder): (&str, &str),
    estimators: &[Estimator],
) -> Result<(Vec<RunLine>, Vec<PairResult>, SceneImages)> {
    let (runs, kinds) = render_runs(args, gpu, (scene, folder), estimators)?;
    eprintln!("verify: {scene} has paths of {}", describe(kinds));
    let lines = runs
        .iter()
        .map(|r| RunLine {
            scene: folder.to_string(),
            label: r.label.clone(),
            frames: r.result.frames,
            seconds: r.result.seconds,
            rejected_samples: r.result.rejected_samples,
            light: r.result.blocks.image().light_and_error(),
        })
        .collect();
    let images = SceneImages {
        scene: folder.to_string(),
        images: runs.iter().map(|r| (r.label.clone(), r.result.image.clone())).collect(),
    };
    Ok((lines, compare_runs(args, settings, folder, &runs, kinds)?, images))
}

/// Renders every estimator on `scene` and writes each run's EXR and PNG into its folder;
/// returns the runs and the vertex kinds of the scene's paths.
fn render_runs(
    args: &VerifyArgs,
    gpu: &Gpu,
    (scene, folder): (&str, &str),
    estimators: &[Estimator],
) -> Result<(Vec<Run>, Kinds)> {
    let mut scenes = Scenes::new(scene);
    let mut runs = Vec::new();
    let mut kinds = None;
    for (i, e) in estimators.iter().enumerate() {
        let decl = e.graph.layouts[&e.layout].clone();
        let kind = scenes.load_for(args.common.bvh, &e.layout, &decl)?;
        kinds.get_or_insert_with(|| scene_kinds(&scenes.get(kind).compiled));
        // A graph that does not handle a feature of the scene (participating media) renders
        // nothing here; the others are compared with each other.
        if let Err(why) = lightgraph::run::graph_handles_scene(&e.graph, scenes.get(kind)) {
            eprintln!("verify: {scene}: {} left out: {why}", e.label);
            continue;
        }
        let loaded = (decl, scenes.shared(kind));
        let run = render_run(args, gpu, loaded, e, i as u32).with_context(|| format!("estimator {}", e.label))?;
        let stem = args.out.join(folder).join(lightgraph::compare::file_stem(&e.label));
        write_exr(
            &stem.with_extension("exr"),
            &run.result.image,
            &[("estimator", e.label.clone())],
        )?;
        write_png(&stem.with_extension("png"), &run.result.image, args.exposure)?;
        runs.push(run);
    }
    Ok((runs, kinds.context("no estimator to verify")?))
}

/// Compares every pair of `runs` of the same quantity on a scene whose paths have `kinds`,
/// writing a map of every pair that differs.
fn compare_runs(
    args: &VerifyArgs,
    settings: &TestSettings,
    folder: &str,
    runs: &[Run],
    kinds: Kinds,
) -> Result<Vec<PairResult>> {
    let mut pairs = Vec::new();
    for (i, a) in runs.iter().enumerate() {
        for b in runs[i + 1..]
            .iter()
            .filter(|b| b.claims.estimates == a.claims.estimates)
        {
            let bias = [a.biased(kinds), b.biased(kinds)];
            let test = compare(&a.result.blocks, &b.result.blocks, settings, [&bias[0], &bias[1]]);
            let gaps = expected_gaps((&a.label, &a.claims), (&b.label, &b.claims), kinds);
            let outcome = Outcome::of(test.verdict, !gaps.is_empty());
            let pair = PairResult {
                scene: folder.to_string(),
                a: a.label.clone(),
                b: b.label.clone(),
                gaps,
                grid_width: a.result.blocks.grid().0,
                test,
                outcome,
            };
            if let Some(map) = map_name(&pair) {
                let images = (&a.result.image, &b.result.image);
                write_map(&args.out.join(map), &pair.test, args.power_settings().block, images)?;
            }
            pairs.push(pair);
        }
    }
    Ok(pairs)
}

/// Renders one estimator on a scene in batches, with a progress bar; `index` makes its seed
/// differ from the other estimators'.
fn render_run(
    args: &VerifyArgs,
    gpu: &Gpu,
    (decl, scene): (LayoutDecl, Arc<LoadedScene>),
    e: &Estimator,
    index: u32,
) -> Result<Run> {
    let seed = args.seed.wrapping_mul(1000).wrapping_add(index);
    let power = args.power_settings();
    let mut common = args.common.clone();
    (common.res, common.spp) = (power.res, power.spp);
    common.set = own_sets(&args.common.set, &e.graph);
    let spec = common.spec(&e.graph.name, Some(&e.layout), seed);
    let mut run = Loaded::with_scene(&spec, e.graph.clone(), (e.layout.clone(), decl), scene)?;
    run.options
        .constants
        .extend(parse_sets(&e.spec.sets, &e.graph, "--graphs @")?);
    let (opts, claims) = (&run.options, claims(&e.graph, &run_constants(&run))?);
    let bar = ProgressBar::new(power.batches as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>32} {bar:30} {pos}/{len} batches {msg} ETA {eta}")
            .expect("valid template"),
    );
    bar.set_prefix(e.label.clone());
    let start = std::time::Instant::now();
    let paths = (opts.width * opts.height * opts.samples_per_frame) as f64;
    let result = render_batches(gpu, &run, (power.budget(), power.block), |done, frames| {
        bar.set_position(done as u64);
        let rate = paths * frames as f64 / start.elapsed().as_secs_f64();
        bar.set_message(format!("{}samples/s", si(rate)));
    })?;
    bar.finish_with_message(format!(
        "{} frames, {}samples/s",
        result.frames,
        si(paths * result.frames as f64 / result.seconds.max(1e-9))
    ));
    Ok(Run {
        label: e.label.clone(),
        claims,
        result,
    })
}

/// The `--set NAME=VALUE` settings whose constant `graph` has: estimators of different graphs
/// share one `--set` list, each taking its own.
fn own_sets(sets: &[String], graph: &Graph) -> Vec<String> {
    sets.iter()
        .filter(|s| {
            s.split_once('=')
                .is_none_or(|(name, _)| constant_names(graph).contains(&name.trim()))
        })
        .cloned()
        .collect()
}
