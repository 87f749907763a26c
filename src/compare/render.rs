//! Running a comparison (`lightgraph compare`, Python's `compare`, each scene of a study):
//! the runs checked against the reference, rendered on one GPU or several for the same
//! budget, their curves and images written and summed up.

use crate::compare::resume::{check_folder, check_settings, finished_runs, write_settings};
use crate::compare::{EstimatorSpec, ReportContext, RunBudget, RunCurve, run, write_report, write_run_images};
use crate::film::{Film, constants_text};
use crate::interrupt::{Interrupted, Signal};
use crate::multi::gpu_selectors;
use crate::run::{Run, RunOptions, Scenes, parse_sets};
use crate::tev::LiveView;
use anyhow::{Result, anyhow, bail};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use lightgraph_engine::Gpu;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

/// Error samples per decade of time unless told.
pub const PER_DECADE: u32 = 6;
/// Each run's budget unless told.
pub const COMPARE_TIME: Duration = Duration::from_secs(10);
/// The folder of a comparison unless told.
pub const COMPARE_OUT: &str = "out/compare";

/// A comparison: runs of one scene against a reference, each for the same budget.
#[derive(Clone)]
pub struct CompareSpec {
    /// The runs' options (scene, resolution and constants not given: the reference's).
    pub options: RunOptions,
    /// The runs, comma-separated `graph[:layout][@NAME=VALUE...]` ([`EstimatorSpec`]).
    pub runs: String,
    /// The reference EXR.
    pub reference: PathBuf,
    /// Continue the comparison in `out`: the runs whose curves are there are not rendered
    /// again.
    pub resume: bool,
    /// The run the others are measured against (None: the first).
    pub baseline: Option<String>,
    /// How the runs are rendered, sampled and written.
    pub comparison: Comparison,
}

/// How the runs of a comparison are rendered, sampled and written: what `compare` and `study`
/// (for each scene's comparison) share.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Each run's budget.
    pub budget: RunBudget,
    /// Error samples per decade of time.
    pub per_decade: u32,
    /// Seed of the runs' random streams (must differ from the references').
    pub seed: u32,
    /// The tev address to stream each run's image to, if any.
    pub tev: Option<String>,
    /// Output folder: a comparison's curves.csv, rmse_vs_time.png, summary.md and each run's
    /// EXR and PNG; a study's summary files and a comparison per scene.
    pub out: PathBuf,
    /// Write into an `out` that holds an earlier comparison (or study), replacing its files;
    /// without it (or `resume`) such a folder is refused before any work
    /// ([`super::resume::check_folder`]).
    pub force: bool,
    /// Exposure of the PNG previews in stops.
    pub exposure: f32,
    /// The GPUs to run on at once, each taking the next run (None: the options' adapter; a
    /// study measures layouts on the first).
    pub gpus: Option<String>,
}

/// Runs the comparison `args` names (its scene, resolution and constants, where not given,
/// the reference's) and returns its summary (Markdown), as written into its folder.
pub fn compare(mut args: CompareSpec) -> Result<String> {
    let reference = Film::read(&args.reference)?;
    args.options.from_reference(&reference);
    let gpus = open_gpus_or_adapter(args.comparison.gpus.as_deref(), args.options.adapter.as_deref())?;
    let mut scenes = Scenes::new(args.options.scene());
    let (summary, _) = compare_with(&args, &reference, &gpus, &mut scenes)?;
    Ok(summary)
}

/// The GPUs `--gpus` names, else the one `--adapter` names.
pub fn open_gpus_or_adapter(gpus: Option<&str>, adapter: Option<&str>) -> Result<Vec<Gpu>> {
    match gpus {
        Some(spec) => open_gpus(spec),
        None => Ok(vec![Gpu::new(adapter)?]),
    }
}

/// Checks the runs of `args` against `reference` (scene, seed, constants, size), renders them
/// on `gpus` with the scene from `scenes` (with `--resume`, those not in `--out` yet) and
/// writes the report into `--out` after every run; returns the summary and the runs' curves
/// in the order of `--runs`. When a signal stopped it, [`Interrupted`] says what was kept.
pub fn compare_with(
    args: &CompareSpec,
    reference: &Film,
    gpus: &[Gpu],
    scenes: &mut Scenes,
) -> Result<(String, Vec<RunCurve>)> {
    check_reference(args, reference)?;
    let c = &args.options;
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
    check_folder(&args.comparison.out, args.comparison.force, args.resume)?;
    let done = match args.resume {
        true => {
            check_settings(&args.comparison.out, &settings)?;
            let pixels = reference.size.0 as usize * reference.size.1 as usize;
            finished_runs(&args.comparison.out, pixels)?
        }
        false => Vec::new(),
    };
    write_settings(&args.comparison.out, &settings)?;
    eprintln!(
        "{} | scene {} (loaded in {:.2} s) | {} runs of {:?}{} | reference {} spp",
        gpus.iter().map(Gpu::describe).collect::<Vec<_>>().join("; "),
        c.scene(),
        scenes.load_seconds(),
        runs.len(),
        args.comparison.budget.time,
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
        budget: args.comparison.budget,
        reference_path: &args.reference,
        reference,
        baseline: labels[baseline],
        run_count: runs.len(),
    };
    let report = |finished: &[RunCurve]| write_report(&args.comparison.out, &ctx, finished);
    let (curves, signal) = run_all(gpus, &runs, args, &ref_mean, done, &report)?;
    let summary = report(&curves)?;
    match signal {
        Some(signal) if curves.len() < runs.len() => Err(Interrupted {
            signal,
            what: format!(
                "{} of {} runs kept in {} (curves.csv, rmse_vs_time.png, summary.md, their EXR and PNG), \
                 the run in flight dropped",
                curves.len(),
                runs.len(),
                args.comparison.out.display()
            ),
        }
        .into()),
        _ => Ok((summary, curves)),
    }
}

/// What a resumed comparison must share with the one it continues: the scene, reference,
/// budget, sampling of the error, device and each run with its options.
fn settings(args: &CompareSpec, reference: &Film, jobs: &[Job], device: &str) -> Vec<(String, String)> {
    let mut settings = vec![
        ("scene".to_string(), args.options.scene().to_string()),
        ("reference".to_string(), args.reference.display().to_string()),
        ("reference spp".to_string(), reference.samples_per_pixel().to_string()),
        ("budget".to_string(), args.comparison.budget.describe()),
        ("per decade".to_string(), args.comparison.per_decade.to_string()),
        ("seed".to_string(), args.comparison.seed.to_string()),
        ("device".to_string(), device.to_string()),
    ];
    for (label, run) in jobs {
        let (layout, kind, opts) = (&run.layout, run.bvh(), &run.options);
        settings.push((format!("run {label}"), format!("{layout} {kind:?} {opts:?}")));
    }
    settings
}

/// Checks that the reference shows the scene of the runs and was rendered with other random
/// numbers than theirs.
pub fn check_reference(args: &CompareSpec, reference: &Film) -> Result<()> {
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    let c = &args.options;
    if c.scene() != info("scene") {
        bail!(
            "{}: the reference shows scene '{}', not '{}'",
            args.reference.display(),
            info("scene"),
            c.scene()
        );
    }
    if info("seed") == args.comparison.seed.to_string() {
        bail!(
            "{}: the reference was rendered with seed {}, the seed of the runs: they would repeat its \
             random numbers and their error would look too small; pass another --seed",
            args.reference.display(),
            args.comparison.seed
        );
    }
    Ok(())
}

/// The runs of `--runs`, each checked against the reference (constants, size) before any
/// renders: a typo should not cost the others' time. Loads the scene with each run's BVH.
fn jobs(args: &CompareSpec, reference: &Film, scenes: &mut Scenes) -> Result<Vec<Job>> {
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    let c = &args.options;
    let specs = EstimatorSpec::parse_list(&args.runs)?;
    let mut runs = Vec::new();
    for spec in &specs {
        let mut run = Run::load_in(
            &c.spec(&spec.graph, spec.layout.as_deref(), args.comparison.seed),
            scenes,
        )?;
        let opts = &run.options;
        if constants_text(&opts.constants) != info("constants") {
            bail!(
                "{}: the reference was made with constants '{}', run {} would use '{}'",
                args.reference.display(),
                info("constants"),
                spec.graph,
                constants_text(&opts.constants)
            );
        }
        reference.check_size(&args.reference, (opts.width, opts.height))?;
        // The run's own settings come after the check: they choose the estimator, not the image.
        let own = parse_sets(&spec.sets, &run.graph, "--runs @")?;
        run.options.constants.extend(own);
        let label = std::iter::once(format!("{}:{}", run.graph.name, run.layout))
            .chain(spec.sets.iter().cloned())
            .collect::<Vec<_>>()
            .join("@");
        runs.push((label, run));
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

/// One run of the comparison: its label and the run (its scene shared with the others').
type Job = (String, Run);

/// Renders the runs of `jobs` not in `done`, each for `--time` on one of `gpus` (one thread
/// per GPU, each taking the next run when its last one ends), with a progress bar per run,
/// writing each run's images and calling `report` with every finished run after each. The
/// first failure, or a signal, stops the GPUs from taking more runs; a run a signal stopped
/// is dropped. Returns the finished runs in the order of `jobs` and the signal, if one came.
fn run_all(
    gpus: &[Gpu],
    jobs: &[Job],
    args: &CompareSpec,
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
            let bar = bars.add(ProgressBar::new(args.comparison.budget.time.as_millis() as u64));
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
        let stop = failure.lock().expect("failure").is_some() || crate::interrupt::requested().is_some();
        (!stop).then(|| next.lock().expect("run queue").next()).flatten()
    };
    std::thread::scope(|scope| {
        for gpu in gpus {
            scope.spawn(|| {
                while let Some(i) = take() {
                    let outcome = run_one(gpu, &jobs[i], args, reference, &progress[i]).and_then(|curve| {
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
    Ok((curves, crate::interrupt::requested()))
}

/// Renders one run on `gpu` with its progress on `bar` (and in tev when asked), writes its
/// images into `--out` and returns its curve.
fn run_one(
    gpu: &Gpu,
    (label, job): &Job,
    args: &CompareSpec,
    reference: &[[f32; 3]],
    bar: &ProgressBar,
) -> Result<RunCurve> {
    let mut view = LiveView::open(
        args.comparison.tev.as_deref(),
        label,
        (job.options.width, job.options.height),
    );
    let result = run(
        gpu,
        job,
        label.clone(),
        args.comparison.budget,
        reference,
        args.comparison.per_decade,
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
    write_run_images(
        &args.comparison.out,
        args.options.scene(),
        &result,
        args.comparison.exposure,
    )?;
    Ok(result.curve)
}
