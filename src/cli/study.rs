//! `lightgraph study`: the best layout of each estimator on a list of scenes, each run given
//! the same wall-clock budget against a reference per scene (given, resumed or rendered by
//! the study), a comparison per scene (as `lightgraph compare` writes it) and one summary.

use super::args::*;
use super::compare::{CompareArgs, check_reference, compare_with, defaults_from_reference, open_gpus_or_adapter};
use super::reference::ReferenceArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::compare::resume::{check_settings, resumable, write_settings};
use lightgraph::compare::{EstimatorSpec, RunBudget};
use lightgraph::interrupt::Interrupted;
use lightgraph::reference::Reference;
use lightgraph::run::{Scenes, load_graph, named_layout, parse_sets};
use lightgraph::study::layouts::{
    Candidate, Choices, LayoutChoice, choices_text, fastest, measure_layouts, parse_choices,
};
use lightgraph::study::summary::{
    EstimatorRun, ReferenceNote, ReferenceSource, SceneRuns, StudyContext, write_summary,
};
use lightgraph::study::{DEFAULT_ESTIMATORS, scene_folders};
use lightgraph_engine::Gpu;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The arguments of `lightgraph study`.
#[derive(Args)]
pub struct StudyArgs {
    #[command(flatten)]
    pub common: Common,
    /// Scenes, comma-separated: built-in names or scene files, as `--scene` takes them (which
    /// `study` does not take).
    #[arg(long, value_delimiter = ',', required = true)]
    pub scenes: Vec<String>,
    /// Estimators, comma-separated: a graph (its layouts are measured on each scene and the
    /// one with the most samples per second runs) or `graph:Layout`, each optionally with
    /// `@NAME=VALUE` constants of its own (as `compare --runs`).
    #[arg(long, default_value = DEFAULT_ESTIMATORS)]
    pub estimators: String,
    /// Wall-clock budget of each estimator on each scene (rendering: its set-up is off the clock unless `--setup-on-clock`).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "20s")]
    pub time: Duration,
    /// Count each run's set-up (pipeline creation, buffers, the first frame's compilation)
    /// on its budget.
    #[arg(long)]
    pub setup_on_clock: bool,
    /// Continue the study in --out (after a signal stopped it): scenes and runs whose results
    /// are there are not rendered again, layouts not measured again; its settings must be
    /// these.
    #[arg(long)]
    pub resume: bool,
    /// Time each layout renders when the study measures a graph's layouts (after a warm-up
    /// frame, so pipeline creation is not measured).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "500ms")]
    pub layout_time: Duration,
    /// Folder of the references, one per scene (`<folder>.exr`, the folder the scene's
    /// outputs get): used when there with enough samples, resumed when there with fewer,
    /// rendered when not there [default: <out>/references].
    #[arg(long)]
    pub references: Option<PathBuf>,
    /// The graph that renders references.
    #[arg(long, default_value = "vcm")]
    pub reference_graph: String,
    /// The layout that renders references (default: the reference graph's).
    #[arg(long)]
    pub reference_layout: Option<String>,
    /// Render seconds each reference must hold; one with fewer is resumed for the rest.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "2m")]
    pub reference_time: Duration,
    /// Frames each reference must hold instead (for reproducible references and tests).
    #[arg(long, conflicts_with = "reference_time", value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub reference_frames: Option<u32>,
    /// Samples per pixel in each frame of references the study renders [default: --spp].
    #[arg(long, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub reference_spp: Option<u32>,
    /// Error samples per decade of time (log-spaced from the first frame to the end, at
    /// least 12).
    #[arg(long, default_value_t = 6, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub per_decade: u32,
    /// Seed of the runs' random streams (must differ from the references').
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    #[command(flatten)]
    pub tev: TevArg,
    /// Output folder: summary.md, summary.csv, layouts.csv, and per scene a folder with
    /// curves.csv, rmse_vs_time.png, summary.md and each run's EXR and PNG.
    #[arg(long, default_value = "out/study")]
    pub out: PathBuf,
    /// Exposure of the PNG previews in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Run on several GPUs of one model at once, as `compare --gpus` (references as
    /// `reference --gpus`; layouts are measured on the first).
    #[arg(long)]
    pub gpus: Option<String>,
}

/// How often a reference being rendered is written, so a stopped study keeps its samples.
const REFERENCE_CHECKPOINT: Duration = Duration::from_secs(300);

/// Runs the study: every scene in turn (reference, layouts, comparison), the summary
/// rewritten after each.
pub fn study(args: StudyArgs) -> Result<()> {
    if let Some(scene) = &args.common.scene {
        bail!("study renders the scenes of --scenes, not --scene {scene}: name it there");
    }
    let folders = scene_folders(&args.scenes)?;
    // Everything named is checked before anything renders: a typo in the last scene or
    // estimator should not cost the others' time.
    for scene in &args.scenes {
        find_scene(scene, "--scenes")?;
    }
    let estimators = estimator_specs(&args.estimators, "--estimators")?;
    let references = references_dir(&args);
    if folders.iter().any(|f| !reference_path(&references, f).exists()) {
        let graph = load_graph(&args.reference_graph).context("--reference-graph")?;
        named_layout(&graph, args.reference_layout.as_deref()).context("--reference-layout")?;
    }
    let gpus = open_gpus_or_adapter(args.gpus.as_deref(), args.common.adapter.as_deref())?;
    let names: Vec<String> = estimators.iter().map(EstimatorSpec::to_string).collect();
    let device = match gpus.len() {
        1 => gpus[0].info.name.clone(),
        n => format!("{} x{n}", gpus[0].info.name),
    };
    let ctx = StudyContext {
        device: &device,
        budget: RunBudget {
            time: args.time,
            setup_on_clock: args.setup_on_clock,
        },
        layout_time: args.layout_time,
        estimators: &names,
        scene_count: args.scenes.len(),
    };
    let settings = settings(&args, &names);
    if args.resume {
        check_settings(&args.out, &settings)?;
    }
    write_settings(&args.out, &settings)?;
    let mut done = Vec::new();
    let mut summary = String::new();
    for (i, (scene, folder)) in args.scenes.iter().zip(&folders).enumerate() {
        eprintln!("study: scene {}/{}: {scene}", i + 1, args.scenes.len());
        let runs = study_scene(&args, (scene, folder), &estimators, &gpus);
        let runs = runs.map_err(|e| stopped(e, &args, done.len(), scene))?;
        done.push(runs);
        // After every scene, so that a study stopped early keeps what it measured.
        summary = write_summary(&args.out, &ctx, &done)?;
    }
    println!(
        "{summary}\nwrote {0}/summary.md, summary.csv, layouts.csv and a comparison per scene in {0}/<scene>/",
        args.out.display()
    );
    Ok(())
}

/// What a resumed study must share with the one it continues (each scene's comparison
/// checks the rest: reference, size, constants, layouts).
fn settings(args: &StudyArgs, estimators: &[String]) -> Vec<(String, String)> {
    let budget = RunBudget {
        time: args.time,
        setup_on_clock: args.setup_on_clock,
    };
    [
        ("scenes", args.scenes.join(",")),
        ("estimators", estimators.join(",")),
        ("budget", budget.describe()),
        ("layout time", format!("{:?}", args.layout_time)),
        ("per decade", args.per_decade.to_string()),
        ("seed", args.seed.to_string()),
    ]
    .map(|(k, v)| (k.to_string(), v))
    .to_vec()
}

/// The error of a scene that failed; when a signal stopped it, [`Interrupted`] saying what
/// the study kept (`scenes_done` scenes before it, and what the scene kept).
fn stopped(error: anyhow::Error, args: &StudyArgs, scenes_done: usize, scene: &str) -> anyhow::Error {
    let Some(i) = error.downcast_ref::<Interrupted>() else {
        return error.context(format!("scene {scene}"));
    };
    let what = format!(
        "{scenes_done} of {} scenes done (summary.md, summary.csv and layouts.csv in {}); scene {scene}: {}; \
         study --resume continues",
        args.scenes.len(),
        args.out.display(),
        i.what
    );
    Interrupted { signal: i.signal, what }.into()
}

/// `--references`, or `<out>/references`.
fn references_dir(args: &StudyArgs) -> PathBuf {
    args.references.clone().unwrap_or_else(|| args.out.join("references"))
}

/// The reference of the scene whose outputs go to `folder`.
fn reference_path(references: &Path, folder: &str) -> PathBuf {
    references.join(format!("{folder}.exr"))
}

/// One scene: its reference, each estimator's layout, the comparison written into
/// `<out>/<folder>`, and what the summary needs of them.
fn study_scene(
    args: &StudyArgs,
    (scene, folder): (&str, &str),
    estimators: &[EstimatorSpec],
    gpus: &[Gpu],
) -> Result<SceneRuns> {
    let path = reference_path(&references_dir(args), folder);
    let (reference, source) = ensure_reference(args, scene, &path)?;
    let mut compare = compare_args(args, (scene, folder), &path);
    defaults_from_reference(&mut compare.common, &reference);
    // As `compare` will check them, before the layouts are measured.
    check_reference(&compare, &reference)?;
    if let Some(size) = compare.common.res {
        check_size(&reference, &path, size)?;
    }
    let mut scenes = Scenes::new(scene);
    let chosen = choose_layouts(args, estimators, &compare, &mut scenes, &gpus[0])?;
    let (runs, choices): (Vec<EstimatorSpec>, Vec<LayoutChoice>) = estimators
        .iter()
        .zip(chosen)
        .map(|(spec, (_, layout, choice))| {
            let run = EstimatorSpec {
                layout: Some(layout),
                ..spec.clone()
            };
            (run, choice)
        })
        .unzip();
    compare.runs = runs.iter().map(EstimatorSpec::to_string).collect::<Vec<_>>().join(",");
    compare.resume = args.resume && resumable(&compare.out);
    let (_, results) = compare_with(&compare, &reference, gpus, &mut scenes)?;
    let runs = estimators
        .iter()
        .zip(runs)
        .zip(choices)
        .zip(results)
        .map(|(((spec, run), choice), result)| EstimatorRun {
            estimator: spec.to_string(),
            layout: run.layout.expect("chosen above"),
            choice,
            samples: result.samples,
        })
        .collect();
    Ok(SceneRuns {
        scene: scene.to_string(),
        folder: folder.to_string(),
        reference: reference_note(&reference, &path, source),
        runs,
    })
}

/// The arguments of the scene's comparison (`lightgraph compare`) against the reference at
/// `path`, its runs still to be named.
fn compare_args(args: &StudyArgs, (scene, folder): (&str, &str), path: &Path) -> CompareArgs {
    CompareArgs {
        common: Common {
            scene: Some(scene.to_string()),
            ..args.common.clone()
        },
        runs: String::new(),
        reference: path.to_path_buf(),
        time: args.time,
        setup_on_clock: args.setup_on_clock,
        resume: false,
        baseline: None,
        per_decade: args.per_decade,
        seed: args.seed,
        tev: args.tev.clone(),
        out: args.out.join(folder),
        exposure: args.exposure,
        gpus: args.gpus.clone(),
    }
}

/// What the summary says of the reference at `path`.
fn reference_note(reference: &Reference, path: &Path, source: ReferenceSource) -> ReferenceNote {
    ReferenceNote {
        path: path.display().to_string(),
        graph: reference.info.get("graph").cloned().unwrap_or_default(),
        samples_per_pixel: reference.samples_per_pixel(),
        seconds: reference.seconds,
        noise_rmse: reference.noise_floor_mse().sqrt(),
        source,
    }
}

/// The layouts file of a scene's folder: each estimator's layout and how it was chosen.
const CHOICES_FILE: &str = "layouts.tsv";

/// Each estimator's layout on the scene of `compare` and how it was chosen: with `--resume`,
/// as the scene's folder recorded them, else by [`choose_layout`]; recorded there.
fn choose_layouts(
    args: &StudyArgs,
    estimators: &[EstimatorSpec],
    compare: &CompareArgs,
    scenes: &mut Scenes,
    gpu: &Gpu,
) -> Result<Choices> {
    let path = compare.out.join(CHOICES_FILE);
    let before = match (args.resume, std::fs::read_to_string(&path)) {
        (true, Ok(text)) => parse_choices(&text).with_context(|| format!("reading {}", path.display()))?,
        _ => Vec::new(),
    };
    let mut chosen = Vec::new();
    for spec in estimators {
        let name = spec.to_string();
        if let Some(earlier) = before.iter().find(|c| c.0 == name) {
            chosen.push(earlier.clone());
            continue;
        }
        if let Some(signal) = lightgraph::interrupt::requested() {
            let what = "stopped measuring its layouts".to_string();
            return Err(Interrupted { signal, what }.into());
        }
        let (layout, choice) = choose_layout(args, spec, &compare.common, scenes, gpu)?;
        chosen.push((name, layout, choice));
    }
    std::fs::create_dir_all(&compare.out).with_context(|| format!("creating {}", compare.out.display()))?;
    std::fs::write(&path, choices_text(&chosen)).with_context(|| format!("writing {}", path.display()))?;
    Ok(chosen)
}

/// The layout `spec` runs in on this scene: the one it names, else the one of its graph's
/// layouts with the most samples per second on the scene (`--layout-time` each).
fn choose_layout(
    args: &StudyArgs,
    spec: &EstimatorSpec,
    common: &Common,
    scenes: &mut Scenes,
    gpu: &Gpu,
) -> Result<(String, LayoutChoice)> {
    if let Some(layout) = &spec.layout {
        return Ok((layout.clone(), LayoutChoice::Named));
    }
    let graph = load_graph(&spec.graph)?;
    let kinds = graph
        .layouts
        .iter()
        .map(|(name, decl)| scenes.load_for(common.bvh, name, decl))
        .collect::<Result<Vec<_>>>()?;
    let candidates: Vec<Candidate> = graph
        .layouts
        .iter()
        .zip(kinds)
        .map(|((name, decl), kind)| (name.as_str(), decl, scenes.get(kind)))
        .collect();
    let scene = candidates.first().map(|c| c.2).context("the graph has no layout")?;
    let mut opts = common.options(scene, &graph, args.seed)?;
    opts.constants.extend(parse_sets(&spec.sets, &graph, "--estimators @")?);
    let bar = ProgressBar::new(candidates.len() as u64);
    bar.set_style(ProgressStyle::with_template("{prefix:>24} {bar:30} {msg}").expect("valid template"));
    bar.set_prefix(format!("{spec}: layouts"));
    let rates = measure_layouts(gpu, &graph, &candidates, &opts, args.layout_time, |rate| {
        bar.inc(1);
        bar.set_message(match &rate.samples_per_second {
            Ok(v) => format!("{} {}samples/s", rate.layout, si(*v)),
            Err(_) => format!("{} failed", rate.layout),
        });
    });
    let best = fastest(&rates).with_context(|| format!("choosing the layout of {spec}"))?;
    bar.finish_with_message(format!("{} chosen", best.layout));
    Ok((best.layout.clone(), LayoutChoice::Measured(rates.clone())))
}

/// What a scene's reference lacks of what the study asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shortfall {
    /// This many frames.
    Frames(u32),
    /// This much render time.
    Time(Duration),
}

/// What the film (none when there is no file yet) lacks of `frames` frames, or of `time`
/// render seconds when no frame count is asked for; `None` when it has enough.
fn shortfall(film: Option<&Reference>, frames: Option<u32>, time: Duration) -> Option<Shortfall> {
    match (film, frames) {
        (None, Some(n)) => Some(Shortfall::Frames(n)),
        (None, None) => Some(Shortfall::Time(time)),
        (Some(film), Some(n)) => {
            let have = u32::try_from(film.frames).unwrap_or(u32::MAX);
            (have < n).then(|| Shortfall::Frames(n - have))
        }
        (Some(film), None) => {
            let have = Duration::from_secs_f64(film.seconds);
            (have < time).then(|| Shortfall::Time(time - have))
        }
    }
}

/// The reference of `scene` at `path`: used as it is when it holds what the study asks for
/// (its settings are checked against the runs as `compare` checks them), resumed when it
/// holds less, rendered with `--reference-graph` when there is none, both by `lightgraph
/// reference`.
fn ensure_reference(args: &StudyArgs, scene: &str, path: &Path) -> Result<(Reference, ReferenceSource)> {
    let film = match path.exists() {
        true => Some(Reference::read(path)?),
        false => None,
    };
    let Some(missing) = shortfall(film.as_ref(), args.reference_frames, args.reference_time) else {
        return Ok((film.expect("only a film lacks nothing"), ReferenceSource::Given));
    };
    let source = match film {
        Some(_) => ReferenceSource::Resumed,
        None => ReferenceSource::Rendered,
    };
    super::reference::reference(reference_args(args, scene, path, source, missing))?;
    Ok((Reference::read(path)?, source))
}

/// The arguments of `lightgraph reference` that render (`source` Rendered) or resume the
/// reference at `path` by `missing`. A resumed film keeps its own graph, layout and samples
/// per frame.
fn reference_args(
    args: &StudyArgs,
    scene: &str,
    path: &Path,
    source: ReferenceSource,
    missing: Shortfall,
) -> ReferenceArgs {
    let new = source == ReferenceSource::Rendered;
    let (time, frames) = match missing {
        Shortfall::Frames(n) => (None, Some(n)),
        Shortfall::Time(t) => (Some(t), None),
    };
    ReferenceArgs {
        common: Common {
            scene: Some(scene.to_string()),
            spp: args.reference_spp.or(args.common.spp).filter(|_| new),
            ..args.common.clone()
        },
        graph: GraphArg {
            graph: new.then(|| args.reference_graph.clone()),
        },
        tev: TevArg { tev: None },
        layout: args.reference_layout.clone().filter(|_| new),
        time,
        frames,
        seed: None,
        resume: (!new).then(|| path.to_path_buf()),
        out: Some(path.to_path_buf()),
        checkpoint: REFERENCE_CHECKPOINT,
        force: false,
        exposure: args.exposure,
        first_frame: None,
        gpus: args.gpus.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn film(frames: u64, seconds: f64) -> Reference {
        let mut r = Reference::new((1, 1), BTreeMap::new());
        r.frames = frames;
        r.seconds = seconds;
        r
    }

    #[test]
    fn a_reference_lacks_what_the_study_asks_beyond_what_it_holds() {
        let minute = Duration::from_secs(60);
        assert_eq!(shortfall(None, Some(8), minute), Some(Shortfall::Frames(8)));
        assert_eq!(shortfall(None, None, minute), Some(Shortfall::Time(minute)));
        assert_eq!(
            shortfall(Some(&film(3, 1.0)), Some(8), minute),
            Some(Shortfall::Frames(5))
        );
        assert_eq!(shortfall(Some(&film(8, 1.0)), Some(8), minute), None);
        assert_eq!(
            shortfall(Some(&film(8, 45.0)), None, minute),
            Some(Shortfall::Time(Duration::from_secs(15)))
        );
        assert_eq!(shortfall(Some(&film(8, 75.0)), None, minute), None);
    }
}
