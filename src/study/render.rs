//! Running a study (`lightgraph study`, Python's `study`): per scene its reference (given,
//! resumed or rendered), each estimator's layout (named or measured) and a comparison, and
//! the summary of all of them.

use crate::compare::render::{CompareSpec, Comparison, check_reference, compare_with, open_gpus_or_adapter};
use crate::compare::resume::{check_folder, check_settings, resumable, write_settings};
use crate::compare::{EstimatorSpec, estimator_specs};
use crate::interrupt::Interrupted;
use crate::output::{Output, check_outputs, si};

use crate::film::Film;
use crate::reference::{REFERENCE_CHECKPOINT, REFERENCE_SEED, ReferenceSpec, render};
use crate::run::scene::find_scene;
use crate::run::{DEFAULT_GRAPH, Run, RunOptions, Scenes, load_graph, named_layout, parse_sets};
use crate::study::html::write_html;
use crate::study::layouts::{Choices, LayoutChoice, choices_text, fastest, measure_layouts, parse_choices};
use crate::study::scene_folders;
use crate::study::summary::{EstimatorRun, ReferenceNote, ReferenceSource, SceneRuns, StudyContext, write_summary};
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph_engine::Gpu;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A study: estimators on scenes, each against a reference per scene.
#[derive(Clone)]
pub struct StudySpec {
    /// The runs' options (a study takes no scene: its scenes are [`StudySpec::scenes`]).
    pub options: RunOptions,
    /// The scenes: built-in names or scene files.
    pub scenes: Vec<String>,
    /// The estimators, comma-separated `graph` or `graph:Layout`, each optionally with
    /// `@NAME=VALUE` constants of its own.
    pub estimators: String,
    /// Continue the study in `out`: what is there is not rendered or measured again.
    pub resume: bool,
    /// Time each layout renders when a graph's layouts are measured.
    pub layout_time: Duration,
    /// Folder of the references, one per scene (None: `<out>/references`).
    pub references: Option<PathBuf>,
    /// The graph that renders references.
    pub reference_graph: String,
    /// The layout that renders references (None: the reference graph's).
    pub reference_layout: Option<String>,
    /// Render seconds each reference must hold.
    pub reference_time: Duration,
    /// Frames each reference must hold instead.
    pub reference_frames: Option<u32>,
    /// Samples per pixel in each frame of references the study renders (None: the options').
    pub reference_spp: Option<u32>,
    /// How each scene's runs are rendered, sampled and written (`out`: the summary files and
    /// a comparison per scene; `gpus`: layouts are measured on the first).
    pub comparison: Comparison,
}

/// The time each layout renders when a study measures a graph's layouts, unless told.
pub const LAYOUT_TIME: Duration = Duration::from_millis(500);
/// Each estimator's budget on each scene unless told.
pub const STUDY_TIME: Duration = Duration::from_secs(20);
/// The render time each reference must hold unless told.
pub const REFERENCE_TIME: Duration = Duration::from_secs(120);
/// The graph that renders a study's references unless told.
pub const REFERENCE_GRAPH: &str = "vcm";
/// The folder of a study unless told.
pub const STUDY_OUT: &str = "out/study";

/// Runs the study: every scene in turn (reference, layouts, comparison), the summary
/// rewritten after each; returns the summary (Markdown).
pub fn study(args: StudySpec) -> Result<String> {
    if let Some(scene) = &args.options.scene {
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
    let gpus = open_gpus_or_adapter(args.comparison.gpus.as_deref(), args.options.adapter.as_deref())?;
    let names: Vec<String> = estimators.iter().map(EstimatorSpec::to_string).collect();
    let device = match gpus.len() {
        1 => gpus[0].info.name.clone(),
        n => format!("{} x{n}", gpus[0].info.name),
    };
    let ctx = StudyContext {
        device: &device,
        budget: args.comparison.budget,
        layout_time: args.layout_time,
        estimators: &names,
        scene_count: args.scenes.len(),
    };
    let settings = settings(&args, &names);
    check_folder(&args.comparison.out, args.comparison.force, args.resume)?;
    check_outputs(&[Output::Folder(&references, &[])], false, None)?;
    if args.resume {
        check_settings(&args.comparison.out, &settings)?;
    }
    write_settings(&args.comparison.out, &settings)?;
    let mut done = Vec::new();
    let mut summary = String::new();
    for (i, (scene, folder)) in args.scenes.iter().zip(&folders).enumerate() {
        eprintln!("study: scene {}/{}: {scene}", i + 1, args.scenes.len());
        let runs = study_scene(&args, (scene, folder), &estimators, &gpus);
        let runs = runs.map_err(|e| stopped(e, &args, done.len(), scene))?;
        done.push(runs);
        // After every scene, so that a study stopped early keeps what it measured.
        summary = write_summary(&args.comparison.out, &ctx, &done)?;
        write_html(&args.comparison.out, &summary, &done)?;
    }
    Ok(summary)
}

/// What a resumed study must share with the one it continues (each scene's comparison
/// checks the rest: reference, size, constants, layouts).
fn settings(args: &StudySpec, estimators: &[String]) -> Vec<(String, String)> {
    [
        ("scenes", args.scenes.join(",")),
        ("estimators", estimators.join(",")),
        ("budget", args.comparison.budget.describe()),
        ("layout time", format!("{:?}", args.layout_time)),
        ("per decade", args.comparison.per_decade.to_string()),
        ("seed", args.comparison.seed.to_string()),
    ]
    .map(|(k, v)| (k.to_string(), v))
    .to_vec()
}

/// The error of a scene that failed; when a signal stopped it, [`Interrupted`] saying what
/// the study kept (`scenes_done` scenes before it, and what the scene kept).
fn stopped(error: anyhow::Error, args: &StudySpec, scenes_done: usize, scene: &str) -> anyhow::Error {
    let Some(i) = error.downcast_ref::<Interrupted>() else {
        return error.context(format!("scene {scene}"));
    };
    let what = format!(
        "{scenes_done} of {} scenes done (summary.md, summary.csv and layouts.csv in {}); scene {scene}: {}",
        args.scenes.len(),
        args.comparison.out.display(),
        i.what
    );
    Interrupted { signal: i.signal, what }.into()
}

/// `--references`, or `<out>/references`.
fn references_dir(args: &StudySpec) -> PathBuf {
    args.references
        .clone()
        .unwrap_or_else(|| args.comparison.out.join("references"))
}

/// The reference of the scene whose outputs go to `folder`.
fn reference_path(references: &Path, folder: &str) -> PathBuf {
    references.join(format!("{folder}.exr"))
}

/// One scene: its reference, each estimator's layout, the comparison written into
/// `<out>/<folder>`, and what the summary needs of them.
fn study_scene(
    args: &StudySpec,
    (scene, folder): (&str, &str),
    estimators: &[EstimatorSpec],
    gpus: &[Gpu],
) -> Result<SceneRuns> {
    let path = reference_path(&references_dir(args), folder);
    let (reference, source) = ensure_reference(args, scene, &path)?;
    let mut compare = compare_args(args, (scene, folder), &path);
    compare.options.from_reference(&reference);
    // As `compare` will check them, before the layouts are measured.
    check_reference(&compare, &reference)?;
    if let Some(size) = compare.options.res {
        reference.check_size(&path, size)?;
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
    compare.resume = args.resume && resumable(&compare.comparison.out);
    let (_, results) = compare_with(&compare, &reference, gpus, &mut scenes)?;
    let runs = estimators
        .iter()
        .zip(runs)
        .zip(choices)
        .zip(results)
        .map(|(((spec, run), choice), result)| EstimatorRun {
            estimator: spec.to_string(),
            layout: run.layout.expect("chosen above"),
            label: result.label,
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
fn compare_args(args: &StudySpec, (scene, folder): (&str, &str), path: &Path) -> CompareSpec {
    CompareSpec {
        options: RunOptions {
            scene: Some(scene.to_string()),
            ..args.options.clone()
        },
        runs: String::new(),
        reference: path.to_path_buf(),
        resume: false,
        baseline: None,
        comparison: Comparison {
            out: args.comparison.out.join(folder),
            ..args.comparison.clone()
        },
    }
}

/// What the summary says of the reference at `path`.
fn reference_note(reference: &Film, path: &Path, source: ReferenceSource) -> ReferenceNote {
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
    args: &StudySpec,
    estimators: &[EstimatorSpec],
    compare: &CompareSpec,
    scenes: &mut Scenes,
    gpu: &Gpu,
) -> Result<Choices> {
    let path = compare.comparison.out.join(CHOICES_FILE);
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
        if let Some(signal) = crate::interrupt::requested() {
            let what = "stopped measuring its layouts".to_string();
            return Err(Interrupted { signal, what }.into());
        }
        let (layout, choice) = choose_layout(args, spec, &compare.options, scenes, gpu)?;
        chosen.push((name, layout, choice));
    }
    std::fs::create_dir_all(&compare.comparison.out)
        .with_context(|| format!("creating {}", compare.comparison.out.display()))?;
    std::fs::write(&path, choices_text(&chosen)).with_context(|| format!("writing {}", path.display()))?;
    Ok(chosen)
}

/// The layout `spec` runs in on this scene: the one it names, else the one of its graph's
/// layouts with the most samples per second on the scene (`--layout-time` each).
fn choose_layout(
    args: &StudySpec,
    spec: &EstimatorSpec,
    common: &RunOptions,
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
    let mut candidates = graph
        .layouts
        .iter()
        .zip(kinds)
        .map(|((name, decl), kind)| {
            let run = common.spec(&graph.name, Some(name), args.comparison.seed);
            Run::with_scene(&run, graph.clone(), (name.clone(), decl.clone()), scenes.shared(kind))
        })
        .collect::<Result<Vec<Run>>>()?;
    if candidates.is_empty() {
        bail!("the graph has no layout");
    }
    let own = parse_sets(&spec.sets, &graph, "--estimators @")?;
    for run in &mut candidates {
        run.options.constants.extend(own.clone());
    }
    let bar = ProgressBar::new(candidates.len() as u64);
    bar.set_style(ProgressStyle::with_template("{prefix:>24} {bar:30} {msg}").expect("valid template"));
    bar.set_prefix(format!("{spec}: layouts"));
    let rates = measure_layouts(gpu, &candidates, args.layout_time, |rate| {
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
fn shortfall(film: Option<&Film>, frames: Option<u32>, time: Duration) -> Option<Shortfall> {
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
fn ensure_reference(args: &StudySpec, scene: &str, path: &Path) -> Result<(Film, ReferenceSource)> {
    let film = match path.exists() {
        true => Some(Film::read(path)?),
        false => None,
    };
    let Some(missing) = shortfall(film.as_ref(), args.reference_frames, args.reference_time) else {
        return Ok((film.expect("only a film lacks nothing"), ReferenceSource::Given));
    };
    let source = match film {
        Some(_) => ReferenceSource::Resumed,
        None => ReferenceSource::Rendered,
    };
    render(reference_spec(args, scene, (path, film), missing))?;
    Ok((Film::read(path)?, source))
}

/// The reference render that renders (no `film` at `path`) or resumes the reference at
/// `path` by `missing`. A resumed film keeps its own graph, layout and samples per frame.
fn reference_spec(
    args: &StudySpec,
    scene: &str,
    (path, film): (&Path, Option<Film>),
    missing: Shortfall,
) -> ReferenceSpec {
    let new = film.is_none();
    let (time, frames) = match missing {
        Shortfall::Frames(n) => (None, Some(n)),
        Shortfall::Time(t) => (Some(t), None),
    };
    let mut options = RunOptions {
        scene: Some(scene.to_string()),
        spp: args.reference_spp.or(args.options.spp).filter(|_| new),
        ..args.options.clone()
    };
    let (mut graph, mut seed) = (new.then(|| args.reference_graph.clone()), None);
    if let Some(film) = &film {
        options.from_film(&mut graph, &mut seed, REFERENCE_SEED, film);
    }
    let layout = args.reference_layout.as_deref().filter(|_| new);
    let graph = graph.as_deref().unwrap_or(DEFAULT_GRAPH);
    ReferenceSpec {
        run: options.spec(graph, layout, seed.unwrap_or(REFERENCE_SEED)),
        time,
        frames,
        resume: film.map(|f| (path.to_path_buf(), f)),
        out: path.to_path_buf(),
        force: false,
        checkpoint: REFERENCE_CHECKPOINT,
        exposure: args.comparison.exposure,
        first_frame: None,
        gpus: args.comparison.gpus.clone(),
        tev: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn film(frames: u64, seconds: f64) -> Film {
        let mut r = Film::new((1, 1), BTreeMap::new());
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
