//! `lightgraph compare`: estimators and layouts against a reference, error against time.

use super::args::*;
use anyhow::{Result, anyhow, bail};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use lightgraph::compare::resume::{check_settings, finished_runs, write_settings};
use lightgraph::compare::{EstimatorSpec, ReportContext, RunBudget, RunCurve, run, write_report, write_run_images};
use lightgraph::interrupt::{Interrupted, Signal};
use lightgraph::multi::gpu_selectors;
use lightgraph::reference::{Reference, constants_text};
use lightgraph::run::{Scenes, SessionOptions, load_graph, named_layout, parse_sets};
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
    /// Count each run's set-up (pipeline creation, buffers, the first frame's compilation)
    /// on its budget; by default its clock starts after it and a warm-up frame (thrown away),
    /// and the set-up is reported beside it.
    #[arg(long)]
    pub setup_on_clock: bool,
    /// Continue the comparison in --out (after a signal stopped it): the runs whose curves
    /// are there are not rendered again; its settings must be these.
    #[arg(long)]
    pub resume: bool,
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
/// on `gpus` with the scene from `scenes` (with `--resume`, those not in `--out` yet) and
/// writes the report into `--out` after every run; returns the summary and the runs' curves
/// in the order of `--runs`. When a signal stopped it, [`Interrupted`] says what was kept.
pub(super) fn compare_with(
    args: &CompareArgs,
    reference: &Reference,
    gpus: &[Gpu],
    scenes: &mut Scenes,
) -> Result<(String, Vec<RunCurve>)> {
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
    let settings = settings(args, reference, &runs, &device);
    let done = match args.resume {
        true => {
            check_settings(&args.out, &settings)?;
            let pixels = reference.size.0 as usize * reference.size.1 as usize;
            finished_runs(&args.out, pixels)?
        }
        false => Vec::new(),
    };
    write_settings(&args.out, &settings)?;
    eprintln!(
        "{} | scene {} (loaded in {:.2} s) | {} runs of {:?}{} | reference {} spp",
        gpus.iter().map(Gpu::describe).collect::<Vec<_>>().join("; "),
        c.scene(),
        scenes.load_seconds(),
        runs.len(),
        args.time,
        match done.len() {
            0 => String::new(),
            n => format!(" ({n} done before)"),
        },
        reference.samples_per_pixel()
    );
    let ref_mean = reference.mean();
    let ctx = ReportContext {
        scene: c.scene(),
        device: &device,
        load_seconds: scenes.load_seconds(),
        budget: budget(args),
        reference_path: &args.reference,
        reference,
        baseline: labels[baseline],
        run_count: runs.len(),
    };
    let report = |finished: &[RunCurve]| write_report(&args.out, &ctx, finished);
    let (curves, signal) = run_all(gpus, scenes, &runs, args, &ref_mean, done, &report)?;
    let summary = report(&curves)?;
    match signal {
        Some(signal) if curves.len() < runs.len() => Err(Interrupted {
            signal,
            what: format!(
                "{} of {} runs kept in {} (curves.csv, rmse_vs_time.png, summary.md, their EXR and PNG), \
                 the run in flight dropped; --resume continues",
                curves.len(),
                runs.len(),
                args.out.display()
            ),
        }
        .into()),
        _ => Ok((summary, curves)),
    }
}

/// What a resumed comparison must share with the one it continues: the scene, reference,
/// budget, sampling of the error, device and each run with its options.
fn settings(args: &CompareArgs, reference: &Reference, jobs: &[Job], device: &str) -> Vec<(String, String)> {
    let mut settings = vec![
        ("scene".to_string(), args.common.scene().to_string()),
        ("reference".to_string(), args.reference.display().to_string()),
        ("reference spp".to_string(), reference.samples_per_pixel().to_string()),
        ("budget".to_string(), budget(args).describe()),
        ("per decade".to_string(), args.per_decade.to_string()),
        ("seed".to_string(), args.seed.to_string()),
        ("device".to_string(), device.to_string()),
    ];
    for (label, _, layout, opts, kind) in jobs {
        settings.push((format!("run {label}"), format!("{layout} {kind:?} {opts:?}")));
    }
    settings
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
    let specs = EstimatorSpec::parse_list(&args.runs)?;
    let mut runs = Vec::new();
    for spec in &specs {
        let graph = load_graph(&spec.graph)?;
        let (layout, decl) = named_layout(&graph, spec.layout.as_deref())?;
        let kind = scenes.load_for(c.bvh, &layout, &decl)?;
        let opts = c.options(scenes.get(kind), &graph, args.seed)?;
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

/// Renders the runs of `jobs` not in `done`, each for `--time` on one of `gpus` (one thread
/// per GPU, each taking the next run when its last one ends), with a progress bar per run,
/// writing each run's images and calling `report` with every finished run after each. The
/// first failure, or a signal, stops the GPUs from taking more runs; a run a signal stopped
/// is dropped. Returns the finished runs in the order of `jobs` and the signal, if one came.
fn run_all(
    gpus: &[Gpu],
    scenes: &Scenes,
    jobs: &[Job],
    args: &CompareArgs,
    reference: &[[f32; 3]],
    done: Vec<RunCurve>,
    report: &(dyn Fn(&[RunCurve]) -> Result<String> + Sync),
) -> Result<(Vec<RunCurve>, Option<Signal>)> {
    let bars = MultiProgress::new();
    let style = ProgressStyle::with_template("{prefix:>24} {bar:30} {msg}").expect("valid template");
    let mut finished: Vec<Option<RunCurve>> = jobs.iter().map(|_| None).collect();
    for curve in done {
        if let Some(i) = jobs.iter().position(|j| j.0 == curve.label) {
            finished[i] = Some(curve);
        }
    }
    let progress: Vec<ProgressBar> = jobs
        .iter()
        .zip(&finished)
        .map(|((label, ..), curve)| {
            let bar = bars.add(ProgressBar::new(args.time.as_millis() as u64));
            bar.set_style(style.clone());
            bar.set_prefix(label.clone());
            if curve.is_some() {
                bar.finish_with_message("done before");
            }
            bar
        })
        .collect();
    let queue: Vec<usize> = (0..jobs.len()).filter(|&i| finished[i].is_none()).collect();
    let next = Mutex::new(queue.into_iter());
    let finished = Mutex::new(finished);
    let failure: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    let take = || {
        let stop = failure.lock().expect("failure").is_some() || lightgraph::interrupt::requested().is_some();
        (!stop).then(|| next.lock().expect("run queue").next()).flatten()
    };
    std::thread::scope(|scope| {
        for gpu in gpus {
            scope.spawn(|| {
                while let Some(i) = take() {
                    let outcome = run_one(gpu, scenes, &jobs[i], args, reference, &progress[i]).and_then(|curve| {
                        let mut finished = finished.lock().expect("finished runs");
                        finished[i] = Some(curve);
                        report(&finished.iter().flatten().cloned().collect::<Vec<_>>())
                    });
                    match outcome {
                        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {}
                        Err(e) => {
                            failure.lock().expect("failure").get_or_insert(e);
                        }
                        Ok(_) => {}
                    }
                }
            });
        }
    });
    if let Some(e) = failure.into_inner().expect("failure") {
        return Err(e);
    }
    let curves = finished
        .into_inner()
        .expect("finished runs")
        .into_iter()
        .flatten()
        .collect();
    Ok((curves, lightgraph::interrupt::requested()))
}

/// Renders one run on `gpu` with its progress on `bar` (and in tev when asked), writes its
/// images into `--out` and returns its curve.
fn run_one(
    gpu: &Gpu,
    scenes: &Scenes,
    (label, graph, layout, opts, kind): &Job,
    args: &CompareArgs,
    reference: &[[f32; 3]],
    bar: &ProgressBar,
) -> Result<RunCurve> {
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
    match &result {
        Ok(_) => bar.finish(),
        Err(_) => bar.abandon_with_message("stopped"),
    }
    let result = result?;
    if let Some(v) = &mut view {
        v.show(&result.image.mean);
    }
    write_run_images(&args.out, args.common.scene(), &result, args.exposure)?;
    Ok(result.curve)
}

/// Each run's budget.
fn budget(args: &CompareArgs) -> RunBudget {
    RunBudget {
        time: args.time,
        setup_on_clock: args.setup_on_clock,
    }
}
