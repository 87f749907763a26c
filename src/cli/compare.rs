//! `lightgraph compare`: estimators and layouts against a reference, error against time.

use super::args::*;
use super::gpus::gpu_selectors;
use anyhow::{Result, anyhow, bail};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use lightgraph::compare::{ReportContext, RunBudget, RunResult, RunSpec, run, write_report};
use lightgraph::reference::{Reference, constants_text};
use lightgraph::render::{SessionOptions, load_graph};
use lightgraph_engine::{Gpu, Graph};
use lightgraph_scenes::bvh::BvhKind;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    /// Runs to compare, comma-separated `graph:layout` (or `graph` for its default layout),
    /// e.g. pt:NaivePTsk,pt:RegenerationPTsk.
    #[arg(long)]
    pub runs: String,
    /// The reference EXR (from `lightgraph reference`); the scene, resolution and constants
    /// default to its own.
    #[arg(long)]
    pub reference: PathBuf,
    /// Wall-clock budget of each run.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "10s")]
    pub time: Duration,
    /// Start each run's clock after its set-up (pipeline creation, buffers), which is then
    /// reported beside it; by default the set-up counts on the budget.
    #[arg(long)]
    pub setup_off_clock: bool,
    /// The run the others are measured against [default: the first].
    #[arg(long)]
    pub baseline: Option<String>,
    /// Error samples per decade of time (log-spaced from the first frame to the end, at
    /// least 12).
    #[arg(long, default_value_t = 6, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub per_decade: u32,
    /// Seed of the runs' random streams (must differ from the reference's).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    #[command(flatten)]
    pub tev: TevArg,
    /// Output folder: curves.csv, rmse_vs_time.png, summary.md and each run's EXR and PNG.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Exposure of the PNG previews in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Run on several GPUs of one model at once, each taking the next run when its last one
    /// ends (every run still has `--time` on one GPU): `all`, the first N adapters, or a
    /// comma-separated list of adapter indices, PCI bus ids or names (`--adapter` is then
    /// not used).
    #[arg(long)]
    pub gpus: Option<String>,
}

pub fn compare(mut args: CompareArgs) -> Result<()> {
    let reference = Reference::read(&args.reference)?;
    defaults_from_reference(&mut args.common, &reference);
    let gpus = open_gpus_or_adapter(args.gpus.as_deref(), args.common.adapter.as_deref())?;
    let mut scenes = Scenes::new(args.common.scene());
    let (summary, _) = compare_with(&args, &reference, &gpus, &mut scenes)?;
    println!(
        "{summary}\nwrote {}/curves.csv, rmse_vs_time.png, summary.md and each run's EXR and PNG",
        args.out.display()
    );
    Ok(())
}

/// Fills the scene, resolution and constants that `common` does not give with the
/// reference's own.
pub(super) fn defaults_from_reference(common: &mut Common, reference: &Reference) {
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    common.scene.get_or_insert_with(|| info("scene"));
    common.res.get_or_insert(reference.size);
    if common.set.is_empty() && common.max_path_length.is_none() {
        common.set = info("constants").split_whitespace().map(String::from).collect();
    }
}

/// The GPUs `--gpus` names, else the one `--adapter` names.
pub(super) fn open_gpus_or_adapter(gpus: Option<&str>, adapter: Option<&str>) -> Result<Vec<Gpu>> {
    match gpus {
        Some(spec) => open_gpus(spec),
        None => Ok(vec![Gpu::new(adapter)?]),
    }
}

/// Checks the runs of `args` against `reference` (scene, seed, constants, size), renders them
/// on `gpus` with the scene from `scenes` and writes the report into `--out`; returns the
/// summary and the runs' results in the order of `--runs`.
pub(super) fn compare_with(
    args: &CompareArgs,
    reference: &Reference,
    gpus: &[Gpu],
    scenes: &mut Scenes,
) -> Result<(String, Vec<RunResult>)> {
    check_reference(args, reference)?;
    let c = &args.common;
    let runs = jobs(args, reference, scenes)?;
    let labels: Vec<&str> = runs.iter().map(|r| r.0.as_str()).collect();
    let baseline = match &args.baseline {
        None => 0,
        Some(b) => match labels.iter().position(|l| l == b || l.ends_with(&format!(":{b}"))) {
            Some(i) => i,
            None => bail!("--baseline {b} is none of the runs ({})", labels.join(", ")),
        },
    };
    let device = match gpus.len() {
        1 => gpus[0].info.name.clone(),
        n => format!("{} x{n}", gpus[0].info.name),
    };
    eprintln!(
        "{} | scene {} (loaded in {:.2} s) | {} runs of {:?} | reference {} spp",
        gpus.iter().map(Gpu::describe).collect::<Vec<_>>().join("; "),
        c.scene(),
        scenes.load_seconds(),
        runs.len(),
        args.time,
        reference.samples_per_pixel()
    );
    let ref_mean = reference.mean();
    let results = run_all(gpus, scenes, runs, args, &ref_mean)?;
    let ctx = ReportContext {
        scene: c.scene(),
        device: &device,
        load_seconds: scenes.load_seconds(),
        budget: budget(args),
        reference_path: &args.reference,
        reference,
        baseline,
    };
    let summary = write_report(&args.out, &ctx, &results, args.exposure)?;
    Ok((summary, results))
}

/// Checks that the reference shows the scene of the runs and was rendered with other random
/// numbers than theirs.
pub(super) fn check_reference(args: &CompareArgs, reference: &Reference) -> Result<()> {
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    let c = &args.common;
    if c.scene() != info("scene") {
        bail!(
            "{}: the reference shows scene '{}', not '{}'",
            args.reference.display(),
            info("scene"),
            c.scene()
        );
    }
    if info("seed") == args.seed.to_string() {
        bail!(
            "{}: the reference was rendered with seed {}, the seed of the runs: they would repeat its \
             random numbers and their error would look too small; pass another --seed",
            args.reference.display(),
            args.seed
        );
    }
    Ok(())
}

/// The runs of `--runs`, each checked against the reference (constants, size) before any
/// renders: a typo should not cost the others' time. Loads the scene with each run's BVH.
fn jobs(args: &CompareArgs, reference: &Reference, scenes: &mut Scenes) -> Result<Vec<Job>> {
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    let c = &args.common;
    let specs = RunSpec::parse_list(&args.runs)?;
    let mut runs = Vec::new();
    for spec in &specs {
        let graph = load_graph(&spec.graph)?;
        let (layout, decl) = named_layout(&graph, spec.layout.as_deref())?;
        let kind = scenes.load_for(c.bvh, &layout, &decl)?;
        let opts = options(c, scenes.get(kind), &graph, args.seed)?;
        if constants_text(&opts.constants) != info("constants") {
            bail!(
                "{}: the reference was made with constants '{}', run {} would use '{}'",
                args.reference.display(),
                info("constants"),
                spec.graph,
                constants_text(&opts.constants)
            );
        }
        check_size(reference, &args.reference, (opts.width, opts.height))?;
        // The run's own settings come after the check: they choose the estimator, not the image.
        let mut opts = opts;
        opts.constants.extend(parse_sets(&spec.sets, &graph, "--runs @")?);
        let label = std::iter::once(format!("{}:{layout}", graph.name))
            .chain(spec.sets.iter().cloned())
            .collect::<Vec<_>>()
            .join("@");
        runs.push((label, graph, layout, opts, kind));
    }
    Ok(runs)
}

/// Opens the GPUs `spec` names (as `render --gpus`); they must be of one model.
fn open_gpus(spec: &str) -> Result<Vec<Gpu>> {
    let mut gpus = Vec::new();
    for (i, selector) in gpu_selectors(spec)?.iter().enumerate() {
        gpus.push(Gpu::new(Some(selector)).map_err(|e| anyhow!("GPU {i} ('{selector}'): {e}"))?);
    }
    if let Some((i, other)) = gpus.iter().enumerate().find(|(_, g)| g.info.name != gpus[0].info.name) {
        bail!(
            "--gpus {spec}: compare needs GPUs of one model (its curves would compare GPUs), but GPU 0 is \
             '{}' and GPU {i} '{}'",
            gpus[0].info.name,
            other.info.name
        );
    }
    Ok(gpus)
}

/// One run of the comparison: its label, graph, layout, options and BVH.
type Job = (String, Graph, String, SessionOptions, BvhKind);

/// Renders every run of `jobs`, each for `--time` on one of `gpus` (one thread per GPU, each
/// taking the next run when its last one ends), with a progress bar per run; the results in
/// the order of `jobs`. The first failure stops the GPUs from taking more runs.
fn run_all(
    gpus: &[Gpu],
    scenes: &Scenes,
    jobs: Vec<Job>,
    args: &CompareArgs,
    reference: &[[f32; 3]],
) -> Result<Vec<RunResult>> {
    let bars = MultiProgress::new();
    let style = ProgressStyle::with_template("{prefix:>24} {bar:30} {msg}").expect("valid template");
    let progress: Vec<ProgressBar> = jobs
        .iter()
        .map(|(label, ..)| {
            let bar = bars.add(ProgressBar::new(args.time.as_millis() as u64));
            bar.set_style(style.clone());
            bar.set_prefix(label.clone());
            bar
        })
        .collect();
    let next = Mutex::new(0usize);
    let results: Mutex<Vec<Option<Result<RunResult>>>> = Mutex::new(jobs.iter().map(|_| None).collect());
    let take = || {
        let mut i = next.lock().expect("run queue");
        let failed = results.lock().expect("results").iter().flatten().any(|r| r.is_err());
        (*i < jobs.len() && !failed).then(|| {
            *i += 1;
            *i - 1
        })
    };
    std::thread::scope(|scope| {
        for gpu in gpus {
            scope.spawn(|| {
                while let Some(i) = take() {
                    let (label, graph, layout, opts, kind) = &jobs[i];
                    let bar = &progress[i];
                    let mut view = args.tev.view(label, (opts.width, opts.height));
                    let result = run(
                        gpu,
                        scenes.get(*kind),
                        graph,
                        (layout, label.clone()),
                        opts.clone(),
                        budget(args),
                        reference,
                        args.per_decade,
                        |t, e, image| {
                            bar.set_position((t * 1e3) as u64);
                            if let Some(e) = e {
                                bar.set_message(format!("{} spp | RMSE {:.4e}", e.samples_per_pixel, e.error.rmse));
                            }
                            if let Some(v) = view.as_mut().filter(|v| v.due()) {
                                v.show(image);
                            }
                        },
                    );
                    bar.finish();
                    if let (Some(v), Ok(r)) = (&mut view, &result) {
                        v.show(&r.image.mean);
                    }
                    results.lock().expect("results")[i] = Some(result);
                }
            });
        }
    });
    // Runs are left untaken only after a failure, which `?` then returns.
    results.into_inner().expect("results").into_iter().flatten().collect()
}

/// Each run's budget.
fn budget(args: &CompareArgs) -> RunBudget {
    RunBudget {
        time: args.time,
        setup_on_clock: !args.setup_off_clock,
    }
}
