//! `import lightgraph`: the renderer from Python. Images come back as float32 numpy arrays of
//! shape (height, width, 3); a bad keyword argument raises `ValueError` naming it
//! (`frames=0: it must be at least 1`), before any work; other errors are `lightgraph.Error`
//! exceptions carrying the CLI's messages (file:line:column for bad scene and graph files).
//! Keyword arguments are the CLI's flags (`max_path_length=8` is `--max-path-length 8`),
//! built into the same typed specs the CLI builds (`RunSpec`, `ReferenceSpec`, `CompareSpec`,
//! `StudySpec`, `ExplainSpec`). The
//! GPU work runs with the interpreter released, so other Python threads go on meanwhile.
//! Every call on one adapter shares one device, opened on first use and kept for the
//! process's life.

mod checks;
mod display;
mod lab;
mod stop;
mod tables;

use ::lightgraph::cli::Cli;
use ::lightgraph::drive::{Budget, Plan, Stopwatch, drive};
use ::lightgraph::explain::{ExplainSpec, report};
use ::lightgraph::film::{DEFAULT_FRAMES, Film, LengthOptions};
use ::lightgraph::reference::{REFERENCE_CHECKPOINT, REFERENCE_SEED, ReferenceSpec, render as render_reference};
use ::lightgraph::run::{Run, RunOptions, RunSpec, Session as RenderSession};
use lightgraph_engine::Gpu;
use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

create_exception!(
    lightgraph,
    Error,
    PyException,
    "An error of lightgraph, with the CLI's message (file:line:column for bad files)."
);

/// The error as a `lightgraph.Error` with the whole chain of causes, as the CLI prints it.
pub(crate) fn err(e: impl Into<anyhow::Error>) -> PyErr {
    Error::new_err(format!("{:#}", e.into()))
}

/// The device of `adapter` (index, PCI bus id or name; the default adapter when absent),
/// opened once per process.
fn gpu(adapter: Option<&str>) -> PyResult<&'static Gpu> {
    static GPUS: OnceLock<Mutex<HashMap<String, &'static Gpu>>> = OnceLock::new();
    let key = adapter.unwrap_or("").to_string();
    let mut gpus = GPUS
        .get_or_init(Default::default)
        .lock()
        .map_err(|_| Error::new_err("device table poisoned"))?;
    if let Some(g) = gpus.get(&key) {
        return Ok(g);
    }
    let opened: &'static Gpu = Box::leak(Box::new(Gpu::new(adapter).map_err(err)?));
    gpus.insert(key, opened);
    Ok(opened)
}

/// Pixels as a float32 array of shape (height, width, 3).
pub(crate) fn array<'py>(
    py: Python<'py>,
    mean: &[[f32; 3]],
    (w, h): (u32, u32),
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let flat: Vec<f32> = mean.iter().flatten().copied().collect();
    PyArray1::from_vec(py, flat).reshape([h as usize, w as usize, 3])
}

/// The scene options shared by `Session`, `render`, `reference` and `explain`.
#[derive(Clone, Copy)]
struct SceneArgs<'a> {
    scene: &'a str,
    graph: &'a str,
    layout: Option<&'a str>,
    spp: u32,
    res: Option<(u32, u32)>,
    max_path_length: Option<u32>,
    bvh: &'a str,
    adapter: Option<&'a str>,
}

impl SceneArgs<'_> {
    /// The run options of these options and `constants`, each checked first (as the CLI
    /// checks its flags, with messages that name the keyword).
    fn options(&self, py: Python<'_>, constants: Option<&Bound<'_, PyDict>>) -> PyResult<RunOptions> {
        checks::constants(py, self.graph, constants)?;
        let sets = constants.into_iter().flat_map(|d| d.iter()).map(|(k, v)| {
            let value = checks::constant_text(&v)?;
            Ok(format!("{}={value}", k.str()?))
        });
        Ok(RunOptions {
            scene: Some(self.scene.to_string()),
            res: self.res,
            spp: Some(self.spp),
            max_path_length: self.max_path_length,
            sets: sets.collect::<PyResult<_>>()?,
            bvh: checks::bvh(self.bvh)?,
            adapter: self.adapter.map(str::to_string),
            ..RunOptions::default()
        })
    }

    /// The run of these options, `constants` and `seed`, each checked first.
    fn spec(&self, py: Python<'_>, constants: Option<&Bound<'_, PyDict>>, seed: u32) -> PyResult<RunSpec> {
        Ok(self.options(py, constants)?.spec(self.graph, self.layout, seed))
    }
}

/// A progressive render: frames accumulate into one image; `render` renders more of them
/// with the interpreter released, `image` reads the mean so far.
///
/// `Session(...)` plans, compiles and instantiates `graph` in `layout` for `scene`; no frame
/// is rendered yet. A bad argument raises ValueError naming it.
///
/// - scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
/// - graph: a built-in graph name or a .ron graph file.
/// - layout: one of the graph's layouts (None: its default).
/// - spp: samples per pixel in each frame, at least 1.
/// - res: (width, height), each at least 1 (None: the scene's).
/// - seed: the seed of the random streams, 0 to 4294967295.
/// - constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
///   constant of the graph, of its type (u32, i32, f32 or bool).
/// - max_path_length: the longest path in segments, at least 1 (None: the scene's).
/// - bvh: "auto", "cwbvh" or "bvh2".
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyclass(module = "lightgraph")]
struct Session {
    session: RenderSession<'static>,
    adapter: String,
    seconds: f64,
}

impl Session {
    /// The session of the run `spec` (a layout must be named or the default: `auto`, which
    /// measures on one GPU, is refused).
    fn open(py: Python<'_>, spec: RunSpec) -> PyResult<Session> {
        let gpu = gpu(spec.adapter.as_deref())?;
        let session = py
            .detach(|| Run::load_named(&spec, "lightgraph.Session")?.session(gpu))
            .map_err(err)?;
        Ok(Session {
            session,
            adapter: gpu.info.name.clone(),
            seconds: 0.0,
        })
    }

    /// Renders until the session holds `frames` frames, or for `time` seconds, through the
    /// driver ([`drive`]), with the interpreter released; at Ctrl-C it stops after the frames
    /// in flight, keeps them and raises `KeyboardInterrupt`.
    fn advance(&mut self, py: Python<'_>, frames: u32, time: Option<f64>) -> PyResult<()> {
        let started = Instant::now();
        let session = &mut self.session;
        let ended = stop::run(py, || {
            let budget = match time {
                Some(t) => Budget::Time(Duration::from_secs_f64(t)),
                None => Budget::Frames(frames.saturating_sub(session.frames) as u64),
            };
            drive(session, Plan::new(budget), &mut Stopwatch::started_at(started), &mut [])?;
            anyhow::Ok(())
        });
        self.seconds += started.elapsed().as_secs_f64();
        match ended {
            stop::Ended::Done(result) => result.map_err(err),
            stop::Ended::Stopped(e, result) => {
                result.map_err(err)?;
                let kept = format!("the session keeps its {} frames (session.image())", self.session.frames);
                Err(stop::stopped(py, e, &kept))
            }
        }
    }
}

#[pymethods]
impl Session {
    /// The session of the arguments the class documents.
    #[new]
    #[pyo3(signature = (scene = "cornell-mitsuba", graph = "pt", layout = None, spp = 1, res = None, seed = 1,
        constants = None, max_path_length = None, bvh = "auto", adapter = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scene: &str,
        graph: &str,
        layout: Option<&str>,
        spp: i64,
        res: Option<(i64, i64)>,
        seed: i64,
        constants: Option<&Bound<'_, PyDict>>,
        max_path_length: Option<i64>,
        bvh: &str,
        adapter: Option<&str>,
    ) -> PyResult<Session> {
        let spp = checks::count("spp", spp)?;
        let res = checks::image(res, spp)?;
        let max_path_length = checks::count_opt("max_path_length", max_path_length)?;
        let seed = checks::seed("seed", seed)?;
        let s = SceneArgs {
            scene,
            graph,
            layout,
            spp,
            res,
            max_path_length,
            bvh,
            adapter,
        };
        let spec = s.spec(py, constants, seed)?;
        Session::open(py, spec)
    }

    /// Renders `frames` more frames, or as many as fit in `time` seconds when given (the GPU
    /// works with the interpreter released). Ctrl-C stops it after the frames in flight and
    /// raises KeyboardInterrupt; the session keeps every frame rendered.
    ///
    /// - frames: frames to add, at least 1.
    /// - time: seconds to render for, above zero (None: render `frames`).
    #[pyo3(signature = (frames = 1, time = None))]
    fn render(&mut self, py: Python<'_>, frames: i64, time: Option<f64>) -> PyResult<()> {
        let frames = checks::count("frames", frames)?;
        let time = checks::seconds_opt("time", time)?;
        let target = self.session.frames.saturating_add(frames);
        self.advance(py, target, time)
    }

    /// The mean image so far, float32 of shape (height, width, 3).
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let image = self.session.image().map_err(err)?;
        array(py, &image.mean, (image.width, image.height))
    }

    /// The mean image so far as a PNG file (bytes; sRGB, 8 bits), as Jupyter shows it.
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        display::png(py, &self.session.image().map_err(err)?, 0.0)
    }

    /// The mean image so far in the reports' viewer (exposure, zoom, values under the
    /// cursor; a self-contained page in an iframe) with its frames, as Jupyter shows it.
    fn _repr_html_(&self, py: Python<'_>) -> PyResult<String> {
        let caption = format!(
            "{} frames, {:.1} s on {}",
            self.session.frames, self.seconds, self.adapter
        );
        display::html(py, &self.session.image().map_err(err)?, "lightgraph session", &caption)
    }

    /// Frames rendered so far.
    #[getter]
    fn frames(&self) -> u32 {
        self.session.frames
    }

    /// Statistics so far: frames, samples (per pixel), rays, seconds (of rendering calls)
    /// and the adapter.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("frames", self.session.frames)?;
        d.set_item("samples", self.session.samples_per_pixel())?;
        d.set_item("rays", self.session.rays())?;
        d.set_item("seconds", self.seconds)?;
        d.set_item("adapter", &self.adapter)?;
        Ok(d)
    }
}

/// Renders `scene` with `graph` for `frames` frames (or for `time` seconds) and returns the
/// mean image (float32, (height, width, 3)) and the statistics (frames, samples, rays,
/// seconds, adapter), as `lightgraph render` with the same options and seed renders it. A
/// bad argument raises ValueError naming it, before any work. Ctrl-C stops it after the
/// frames in flight and raises KeyboardInterrupt carrying the film so far as its `image` and
/// `stats`.
///
/// - scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
/// - graph: a built-in graph name or a .ron graph file.
/// - layout: one of the graph's layouts (None: its default).
/// - spp: samples per pixel in each frame, at least 1.
/// - res: (width, height), each at least 1 (None: the scene's).
/// - seed: the seed of the random streams, 0 to 4294967295.
/// - frames: frames to render, at least 1.
/// - time: seconds to render for, above zero (None: render `frames`).
/// - constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
///   constant of the graph, of its type (u32, i32, f32 or bool).
/// - max_path_length: the longest path in segments, at least 1 (None: the scene's).
/// - bvh: "auto", "cwbvh" or "bvh2".
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyfunction]
#[pyo3(signature = (scene = "cornell-mitsuba", graph = "pt", layout = None, spp = 1, res = None, seed = 1,
    frames = 64, time = None, constants = None, max_path_length = None, bvh = "auto", adapter = None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &str,
    graph: &str,
    layout: Option<&str>,
    spp: i64,
    res: Option<(i64, i64)>,
    seed: i64,
    frames: i64,
    time: Option<f64>,
    constants: Option<&Bound<'_, PyDict>>,
    max_path_length: Option<i64>,
    bvh: &str,
    adapter: Option<&str>,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyDict>)> {
    let frames = checks::count("frames", frames)?;
    let time = checks::seconds_opt("time", time)?;
    let mut s = Session::new(
        py,
        scene,
        graph,
        layout,
        spp,
        res,
        seed,
        constants,
        max_path_length,
        bvh,
        adapter,
    )?;
    if let Err(e) = s.advance(py, frames, time) {
        if e.is_instance_of::<PyKeyboardInterrupt>(py) {
            // The film so far rides on the exception.
            e.value(py).setattr("image", s.image(py)?)?;
            e.value(py).setattr("stats", s.stats(py)?)?;
        }
        return Err(e);
    }
    Ok((s.image(py)?, s.stats(py)?))
}

/// How the module names the options of a run's length in its messages: `frames=256`.
const PYTHON_LENGTH_OPTIONS: LengthOptions = LengthOptions {
    frames: "frames",
    time: "time",
    resume: "resume",
    joiner: "=",
};

/// Renders a reference film as `lightgraph reference` does (f64 sums and variance, the
/// settings, a PNG preview) for `frames` frames or `time` seconds, writes it to `out`, and
/// returns its mean image. A bad argument raises ValueError naming it, before any work.
/// Ctrl-C stops it after the frames in flight, writes the film and raises
/// KeyboardInterrupt saying so.
///
/// - out: the film's path (an EXR; the PNG preview goes beside it).
/// - scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
/// - graph: a built-in graph name or a .ron graph file.
/// - layout: one of the graph's layouts (None: its default).
/// - spp: samples per pixel in each frame, at least 1.
/// - res: (width, height), each at least 1 (None: the scene's).
/// - seed: the seed of the random streams, 0 to 4294967295 (None: 1000003).
/// - frames: the frames the film holds at the end, at least 1 (64 when neither frames nor
///   time is given); with resume, its frames included (a film of 64 frames resumed with
///   frames=256 gets 192 more; one that holds as many already raises ValueError before any
///   work).
/// - time: seconds to render for, above zero (with resume, the time added to the film's).
/// - constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
///   constant of the graph, of its type (u32, i32, f32 or bool).
/// - max_path_length: the longest path in segments, at least 1 (None: the scene's).
/// - bvh: "auto", "cwbvh" or "bvh2".
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
/// - resume: a film to continue with more frames of the same random streams (its
///   resolution, seed and constants are the defaults of those not given; scene, graph and
///   spp must be its own).
#[pyfunction]
#[pyo3(signature = (scene = "cornell-mitsuba", out = PathBuf::from("out/reference.exr"), graph = "pt", layout = None,
    spp = 1, res = None, seed = None, frames = None, time = None, constants = None, max_path_length = None,
    bvh = "auto", adapter = None, resume = None))]
#[allow(clippy::too_many_arguments)]
fn reference<'py>(
    py: Python<'py>,
    scene: &str,
    out: PathBuf,
    graph: &str,
    layout: Option<&str>,
    spp: i64,
    res: Option<(i64, i64)>,
    seed: Option<i64>,
    frames: Option<i64>,
    time: Option<f64>,
    constants: Option<&Bound<'_, PyDict>>,
    max_path_length: Option<i64>,
    bvh: &str,
    adapter: Option<&str>,
    resume: Option<PathBuf>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let spp = checks::count("spp", spp)?;
    let res = checks::image(res, spp)?;
    let (seed, frames) = (checks::seed_opt("seed", seed)?, checks::count_opt("frames", frames)?);
    let time = checks::seconds_opt("time", time)?;
    let max_path_length = checks::count_opt("max_path_length", max_path_length)?;
    let s = SceneArgs {
        scene,
        graph,
        layout,
        spp,
        res,
        max_path_length,
        bvh,
        adapter,
    };
    let mut options = s.options(py, constants)?;
    let (mut graph, mut seed) = (Some(graph.to_string()), seed);
    // The frames in all, as the CLI's --frames; the spec's are those this call adds.
    let mut frames = frames.or(time.is_none().then_some(DEFAULT_FRAMES));
    let resume = match resume {
        Some(path) => {
            let film = Film::read(&path).map_err(err)?;
            options.from_film(&mut graph, &mut seed, REFERENCE_SEED, &film);
            if let (Some(total), None) = (frames, time) {
                let left = film.frames_left(total, &path, &PYTHON_LENGTH_OPTIONS);
                frames = Some(left.map_err(|e| PyValueError::new_err(format!("{e:#}")))?);
            }
            Some((path, film))
        }
        None => None,
    };
    let graph = graph.expect("given");
    let spec = ReferenceSpec {
        run: options.spec(&graph, layout, seed.unwrap_or(REFERENCE_SEED)),
        time: time.map(Duration::from_secs_f64),
        frames,
        resume,
        out: out.clone(),
        force: false,
        checkpoint: REFERENCE_CHECKPOINT,
        exposure: 0.0,
        first_frame: None,
        gpus: None,
        tev: None,
    };
    stop::interruptible(py, || render_reference(spec))?;
    let film = Film::read(&out).map_err(err)?;
    array(py, &film.mean(), film.size)
}

/// The kernels, schedule and resources of `graph`'s layouts (all of them, or `layout`) for
/// `scene`, as `lightgraph explain` prints them.
///
/// - graph: a built-in graph name or a .ron graph file.
/// - layout: one of the graph's layouts (None: all of them).
/// - scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
/// - res: (width, height), each at least 1 (None: the scene's).
/// - spp: samples per pixel in each frame, at least 1.
/// - constants: graph constants to values; each must be a constant of the graph, of its type.
/// - all_features: compile every scene feature into the kernels, not only the scene's.
/// - adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
#[pyfunction]
#[pyo3(signature = (graph = "pt", layout = None, scene = "cornell-mitsuba", res = None, spp = 1, constants = None,
    all_features = false, adapter = None))]
#[allow(clippy::too_many_arguments)]
fn explain(
    py: Python<'_>,
    graph: &str,
    layout: Option<&str>,
    scene: &str,
    res: Option<(i64, i64)>,
    spp: i64,
    constants: Option<&Bound<'_, PyDict>>,
    all_features: bool,
    adapter: Option<&str>,
) -> PyResult<String> {
    let spp = checks::count("spp", spp)?;
    let res = checks::image(res, spp)?;
    let s = SceneArgs {
        scene,
        graph,
        layout,
        spp,
        res,
        max_path_length: None,
        bvh: "auto",
        adapter,
    };
    let mut options = s.options(py, constants)?;
    options.overrides.all_features = all_features;
    let spec = ExplainSpec {
        options,
        graph: graph.to_string(),
        layout: layout.map(str::to_string),
        dot: None,
        wgsl: None,
    };
    py.detach(|| report(&spec)).map_err(err)
}

/// What this installation offers: built-in scenes (name to file), graphs, and the GPU
/// adapters (as `lightgraph list` shows them).
#[pyfunction(name = "list")]
fn list_all(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let scenes = PyDict::new(py);
    for (name, path) in ::lightgraph::assets::scene_names() {
        scenes.set_item(name, path)?;
    }
    d.set_item("scenes", scenes)?;
    d.set_item("graphs", PyList::new(py, ::lightgraph::assets::graph_names())?)?;
    let adapters: Vec<String> = lightgraph_engine::gpu::adapters()
        .iter()
        .enumerate()
        .map(|(i, a)| lightgraph_engine::gpu::describe_adapter(i, a))
        .collect();
    d.set_item("adapters", PyList::new(py, adapters)?)?;
    Ok(d)
}

/// Reads a film (an EXR from `render`, `reference` or `merge`): its mean image and a dict of
/// its settings and statistics (the EXR's attributes, as text) with `samples` (per pixel),
/// `frames` and `seconds`.
///
/// - path: the film's path.
#[pyfunction]
fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyDict>)> {
    let film = Film::read(&path).map_err(err)?;
    let d = PyDict::new(py);
    for (k, v) in &film.info {
        d.set_item(k, v)?;
    }
    d.set_item("samples", film.samples_per_pixel())?;
    d.set_item("frames", film.frames)?;
    d.set_item("seconds", film.seconds)?;
    Ok((array(py, &film.mean(), film.size)?, d))
}

/// Runs a `lightgraph` command line (without the program name), e.g.
/// `cli(["merge", "a.exr", "b.exr", "--out", "m.exr"])`; its output goes to the process's
/// stdout and stderr, its errors raise lightgraph.Error with the CLI's message.
///
/// - args: the command and its options, as strings.
#[pyfunction]
fn cli(py: Python<'_>, args: Vec<String>) -> PyResult<()> {
    let argv = std::iter::once("lightgraph".to_string()).chain(args);
    let command = Cli::parse_from_args(argv).map_err(err)?;
    stop::interruptible(py, || command.run())
}

/// The module `lightgraph`.
#[pymodule(name = "lightgraph")]
fn lightgraph_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set on import, before this module starts a thread or opens Vulkan; the
        // Vulkan loader reads it, and warns twice a call when it is unset.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // numpy's C API now, not at the first image: a Ctrl-C pending then would fail its import.
    PyArray1::<f32>::zeros(m.py(), 0, false);
    m.add("Error", m.py().get_type::<Error>())?;
    m.add_class::<Session>()?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(reference, m)?)?;
    m.add_function(wrap_pyfunction!(lab::compare, m)?)?;
    m.add_function(wrap_pyfunction!(lab::study, m)?)?;
    m.add_function(wrap_pyfunction!(lab::verify, m)?)?;
    m.add_function(wrap_pyfunction!(display::to_png, m)?)?;
    m.add_function(wrap_pyfunction!(explain, m)?)?;
    m.add_function(wrap_pyfunction!(list_all, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    Ok(())
}
