//! The lab's commands from Python: `compare`, `study` and `verify` run as the CLI runs them
//! (writing the same files) and return what they found as Python values: the summary
//! (Markdown), the tables (pandas DataFrames, or dicts of numpy arrays without pandas) and
//! the images (float32 numpy arrays keyed by run).

use crate::tables::{images, table};
use crate::{checks, err, stop};
use ::lightgraph::cli::Cli;
use ::lightgraph::compare::RunBudget;
use ::lightgraph::compare::render::{
    COMPARE_OUT, COMPARE_TIME, CompareSpec, Comparison, PER_DECADE, compare as run_compare,
};
use ::lightgraph::film::Film;
use ::lightgraph::run::{DEFAULT_SEED, RunOptions};
use ::lightgraph::study::render::{
    LAYOUT_TIME, REFERENCE_GRAPH, REFERENCE_TIME, STUDY_OUT, STUDY_TIME, StudySpec, study as run_study,
};
use ::lightgraph::study::{DEFAULT_ESTIMATORS, scene_folders};
use ::lightgraph::verify::DEFAULT_SCENES as VERIFY_SCENES;
use ::lightgraph::verify::preset::Preset;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// Whether the file at `path` was written at or after `time`.
fn written_since(path: &Path, time: SystemTime) -> bool {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .is_ok_and(|m| m >= time)
}

/// The folder of verify's results unless told.
const VERIFY_OUT: &str = "out/verify";

/// A comparison's folder read back: `curves` (curves.csv), `images` (each run's EXR by label).
fn comparison_found<'py>(py: Python<'py>, dir: &Path) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("curves", table(py, &dir.join("curves.csv"))?)?;
    d.set_item("images", images(py, dir)?)?;
    Ok(d)
}

/// The reference film at `path`'s mean image.
fn reference_image<'py>(py: Python<'py>, path: &Path) -> PyResult<Bound<'py, PyAny>> {
    let film = Film::read(path).map_err(err)?;
    Ok(crate::array(py, &film.mean(), film.size)?.into_any())
}

/// Runs each of `runs` for `time` seconds against the reference film `reference`, as
/// `lightgraph compare` does, and writes the comparison into `out` (curves.csv,
/// rmse_vs_time.png, summary.md, each run's EXR and PNG). Returns a dict: `summary` (the
/// Markdown), `curves` (curves.csv: each run's error over time, as a pandas DataFrame, or a
/// dict of numpy arrays without pandas), `images` (each run's mean image by run label) and
/// `reference` (the reference's mean image), images as float32 arrays of shape
/// (height, width, 3). Ctrl-C stops it after the frames in flight (KeyboardInterrupt saying
/// what was kept).
///
/// - reference: the reference film (from `reference`).
/// - runs: `graph[:layout][@NAME=VALUE...]`, comma-separated.
/// - time: seconds each run renders for, above zero.
/// - seed: the seed of the random streams, 0 to 4294967295.
/// - out: the folder of the comparison.
/// - per_decade: error samples per decade of time, at least 1.
/// - baseline: the run the others' speed-ups are against (None: the first).
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyfunction]
#[pyo3(signature = (reference, runs, time = COMPARE_TIME.as_secs_f64(), seed = DEFAULT_SEED as i64,
    out = PathBuf::from(COMPARE_OUT), per_decade = PER_DECADE as i64, baseline = None, adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn compare<'py>(
    py: Python<'py>,
    reference: PathBuf,
    runs: &str,
    time: f64,
    seed: i64,
    out: PathBuf,
    per_decade: i64,
    baseline: Option<&str>,
    adapter: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let time = checks::seconds("time", time)?;
    let (seed, per_decade) = (checks::seed("seed", seed)?, checks::count("per_decade", per_decade)?);
    let spec = CompareSpec {
        options: RunOptions {
            adapter: adapter.map(str::to_string),
            ..RunOptions::default()
        },
        runs: runs.to_string(),
        reference: reference.clone(),
        resume: false,
        baseline: baseline.map(str::to_string),
        comparison: comparison(time, per_decade, seed, out.clone()),
    };
    let summary = stop::interruptible(py, || run_compare(spec))?;
    let found = comparison_found(py, &out)?;
    found.set_item("summary", summary)?;
    found.set_item("reference", reference_image(py, &reference)?)?;
    Ok(found)
}

/// The comparison of runs of `seconds` each (set-up off the clock), `per_decade` error samples
/// a decade, `seed`, written into `out`, on the options' adapter, as the CLI's defaults leave
/// the rest.
fn comparison(seconds: f64, per_decade: u32, seed: u32, out: PathBuf) -> Comparison {
    Comparison {
        budget: RunBudget {
            time: Duration::from_secs_f64(seconds),
            setup_on_clock: false,
        },
        per_decade,
        seed,
        tev: None,
        out,
        // The module replaces an earlier comparison's files, as it always has.
        force: true,
        exposure: 0.0,
        gpus: None,
    }
}

/// Runs `lightgraph study`: each estimator on each scene against a reference per scene, and
/// writes each scene's comparison and the summary files into `out`. Returns a dict: `summary`
/// (the Markdown), `table` (summary.csv: a row per scene and estimator), `layouts`
/// (layouts.csv), and `scenes`: per scene folder a dict of `curves` (its curves.csv),
/// `images` (each run's mean image by run label) and `reference` (its reference's mean
/// image). Tables are pandas DataFrames (dicts of numpy arrays without pandas), images
/// float32 arrays of shape (height, width, 3). Ctrl-C stops it after the frames in flight
/// (KeyboardInterrupt saying what was kept).
///
/// - scenes: the scenes, as `scene` of `render` takes them.
/// - estimators: `graph` (its fastest layout on each scene) or `graph:Layout` entries
///   (None: PT, LVC-BPT, PPM, SPPM, PBPM and VCM).
/// - time: seconds of rendering per estimator and scene, above zero.
/// - reference_time: seconds of each missing reference, above zero (found in, resumed into
///   or rendered into `out/references`).
/// - reference_graph: the graph that renders the references.
/// - res: (width, height), each at least 1 (None: each scene's).
/// - seed: the seed of the random streams, 0 to 4294967295.
/// - out: the folder of the study.
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyfunction]
#[pyo3(signature = (scenes, estimators = None, time = STUDY_TIME.as_secs_f64(),
    reference_time = REFERENCE_TIME.as_secs_f64(), reference_graph = REFERENCE_GRAPH, res = None,
    seed = DEFAULT_SEED as i64, out = PathBuf::from(STUDY_OUT), adapter = None))]
#[allow(clippy::too_many_arguments)]
pub fn study<'py>(
    py: Python<'py>,
    scenes: Vec<String>,
    estimators: Option<Vec<String>>,
    time: f64,
    reference_time: f64,
    reference_graph: &str,
    res: Option<(i64, i64)>,
    seed: i64,
    out: PathBuf,
    adapter: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let time = checks::seconds("time", time)?;
    let reference_time = checks::seconds("reference_time", reference_time)?;
    let (res, seed) = (checks::image(res, 1)?, checks::seed("seed", seed)?);
    let folders = scene_folders(&scenes).map_err(err)?;
    let spec = StudySpec {
        options: RunOptions {
            res,
            adapter: adapter.map(str::to_string),
            ..RunOptions::default()
        },
        scenes,
        estimators: estimators.map_or_else(|| DEFAULT_ESTIMATORS.to_string(), |e| e.join(",")),
        resume: false,
        layout_time: LAYOUT_TIME,
        references: None,
        reference_graph: reference_graph.to_string(),
        reference_layout: None,
        reference_time: Duration::from_secs_f64(reference_time),
        reference_frames: None,
        reference_spp: None,
        comparison: comparison(time, PER_DECADE, seed, out.clone()),
    };
    let summary = stop::interruptible(py, || run_study(spec))?;
    let found = PyDict::new(py);
    found.set_item("summary", summary)?;
    found.set_item("table", table(py, &out.join("summary.csv"))?)?;
    found.set_item("layouts", table(py, &out.join("layouts.csv"))?)?;
    let per_scene = PyDict::new(py);
    for folder in folders {
        let scene = comparison_found(py, &out.join(&folder))?;
        let reference = out.join("references").join(format!("{folder}.exr"));
        scene.set_item("reference", reference_image(py, &reference)?)?;
        per_scene.set_item(folder, scene)?;
    }
    found.set_item("scenes", per_scene)?;
    Ok(found)
}

/// Runs `lightgraph verify`: every estimator renders every scene in batches, and every pair is
/// tested block by block and as a whole for a difference beyond their noise (docs/verify.md);
/// writes verify.md, verify.csv, each run's EXR and PNG per scene folder and a map of every
/// pair that differs into `out`. Returns a dict: `summary` (the Markdown), `table`
/// (verify.csv: a row per scene and pair with the verdict and its numbers; a pandas DataFrame,
/// or a dict of numpy arrays without pandas) and `scenes`: per scene folder a dict of `images`
/// (each estimator's mean image, float32 of shape (height, width, 3)), and `failed`: None, or
/// the message with which the command fails (a difference nothing predicts, or pairs the
/// budget could not decide), which comes with the tables rather than raising.
///
/// - scenes: the scenes, as `scene` of `render` takes them (None: the six Cornell boxes).
/// - graphs: estimators, `graph[:Layout][@NAME=VALUE...]` entries (None: every built-in
///   graph of radiance, and VCM's two halves alone).
/// - add: estimators verified besides those of `graphs`, e.g. your own graph file.
/// - time: seconds each estimator renders each scene, above zero (None: the preset's budget,
///   else 10).
/// - frames: frames of each estimator on each scene instead of a time (reproducible; it wins
///   over `time`).
/// - batches: batches each run is split into, at least 2 (the samples of the errors; None: the
///   preset's, else 16).
/// - block: side of the blocks compared, in pixels, at least 1 (None: the preset's, else 16).
/// - res: (width, height), each at least 1 (None: the preset's, else each scene's).
/// - preset: "lavapipe" or "gpu": the size, samples per pixel, budget, batches, blocks and
///   power of `lightgraph verify --preset` (docs/verify.md; lavapipe's for a software
///   rasteriser, gpu's for a GPU). Each of time, frames, batches, block and res given wins.
/// - seed: the seed of the random streams, 0 to 4294967295.
/// - out: the folder of the verification.
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyfunction]
#[pyo3(signature = (scenes = None, graphs = None, add = None, time = None, frames = None, batches = None,
    block = None, res = None, seed = 1, out = PathBuf::from(VERIFY_OUT), adapter = None, preset = None))]
#[allow(clippy::too_many_arguments)]
pub fn verify<'py>(
    py: Python<'py>,
    scenes: Option<Vec<String>>,
    graphs: Option<Vec<String>>,
    add: Option<Vec<String>>,
    time: Option<f64>,
    frames: Option<i64>,
    batches: Option<i64>,
    block: Option<i64>,
    res: Option<(i64, i64)>,
    seed: i64,
    out: PathBuf,
    adapter: Option<&str>,
    preset: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let time = checks::seconds_opt("time", time)?;
    let frames = checks::count_opt("frames", frames)?;
    let batches = checks::count_opt("batches", batches)?;
    if let Some(b) = batches.filter(|b| *b < 2) {
        return Err(PyValueError::new_err(format!("batches={b}: it must be at least 2")));
    }
    let (block, seed) = (checks::count_opt("block", block)?, checks::seed("seed", seed)?);
    let res = checks::image(res, 1)?;
    if let Some(name) = preset {
        Preset::named(name).map_err(|e| PyValueError::new_err(format!("preset='{name}': {e}")))?;
    }
    let scenes = scenes.unwrap_or_else(|| VERIFY_SCENES.split(',').map(str::to_string).collect());
    let folders = scene_folders(&scenes).map_err(err)?;
    let mut args: Vec<String> = vec![
        "lightgraph".into(),
        "verify".into(),
        "--scenes".into(),
        scenes.join(","),
    ];
    let mut flag = |name: &str, value: String| args.extend([format!("--{name}"), value]);
    match (frames, time) {
        (Some(n), _) => flag("frames", n.to_string()),
        (None, Some(t)) => flag("time", format!("{}ms", (t * 1000.0).round().max(1.0))),
        (None, None) => {}
    }
    for (name, value) in [("batches", batches), ("block", block)] {
        if let Some(v) = value {
            flag(name, v.to_string());
        }
    }
    if let Some(name) = preset {
        flag("preset", name.to_string());
    }
    flag("seed", seed.to_string());
    flag("out", out.display().to_string());
    for (name, value) in [("graphs", graphs), ("add", add)] {
        if let Some(v) = value {
            flag(name, v.join(","));
        }
    }
    if let Some((w, h)) = res {
        flag("res", format!("{w}x{h}"));
    }
    if let Some(a) = adapter {
        flag("adapter", a.to_string());
    }
    let command = Cli::parse_from_args(args).map_err(err)?;
    let started = SystemTime::now();
    let failed = match stop::interruptible(py, || command.run()) {
        Ok(()) => None,
        // A verdict that fails the command (a pair differing unexpectedly, or undecided) comes
        // after the tables: they are returned with it.
        Err(e) if e.is_instance_of::<crate::Error>(py) && written_since(&out.join("verify.csv"), started) => {
            Some(e.value(py).str()?.to_string())
        }
        Err(e) => return Err(e),
    };
    let found = PyDict::new(py);
    found.set_item("failed", failed)?;
    let summary = std::fs::read_to_string(out.join("verify.md")).map_err(err)?;
    found.set_item("summary", summary)?;
    found.set_item("table", table(py, &out.join("verify.csv"))?)?;
    let per_scene = PyDict::new(py);
    for folder in folders {
        let scene = PyDict::new(py);
        scene.set_item("images", images(py, &out.join(&folder))?)?;
        per_scene.set_item(folder, scene)?;
    }
    found.set_item("scenes", per_scene)?;
    Ok(found)
}
