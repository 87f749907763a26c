//! Rendering a reference (`lightgraph reference`, Python's `reference`): a long render of a
//! run accumulated in f64 on the host, with its variance, written as a reference EXR with a
//! PNG preview and resumable, on one GPU or several.

use crate::checkpoint::{Checkpoint, Filmed, write_with_preview};
use crate::drive::{Budget, Observer, Plan, Stopwatch, drive};
use crate::film::{Film, film_settings};
use crate::interrupt::stopped_by_signal;
use crate::multi::{gpu_selectors, render_on_gpus};
use crate::output::{check_out, shell_word, si};
use crate::run::{Run, RunSpec};
use crate::tev::LiveView;
use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph_engine::Gpu;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The default seed of references: not the default of `render` and `compare` (1), so runs
/// compared with a reference draw other random numbers than it did.
pub const REFERENCE_SEED: u32 = 1_000_003;

/// How often a reference being rendered is written unless told, so a stopped render keeps
/// its samples.
pub const REFERENCE_CHECKPOINT: Duration = Duration::from_secs(300);

/// A reference render: the run, how long, where it goes and what it resumes.
pub struct ReferenceSpec {
    /// The run (its settings filled from the resumed film's where not given:
    /// [`crate::run::RunOptions::from_film`]); its first frame is [`ReferenceSpec::first_frame`].
    pub run: RunSpec,
    /// Render for this long (added to what a resumed reference has).
    pub time: Option<Duration>,
    /// Render this many frames (when no time is given): those added to a resumed film (the
    /// command line's `--frames` and Python's `frames=` count its frames too, and give this
    /// the frames it lacks: [`Film::frames_left`]).
    pub frames: Option<u32>,
    /// The film to add samples to, and its path.
    pub resume: Option<(PathBuf, Film)>,
    /// The EXR written; the PNG preview goes beside it.
    pub out: PathBuf,
    /// Replace an existing `out` that is not the resumed film.
    pub force: bool,
    /// How often the film is written while rendering.
    pub checkpoint: Duration,
    /// Exposure of the PNG preview in stops.
    pub exposure: f32,
    /// Frame index of the first frame (None: where the resumed film ends, or 0).
    pub first_frame: Option<u32>,
    /// The GPUs to render on at once (`render --gpus`); None: the run's adapter.
    pub gpus: Option<String>,
    /// The tev address to stream the image to, if any.
    pub tev: Option<String>,
}

/// How often the GPU's f32 sums are moved into the host's f64 ones.
const ABSORB_EVERY: Duration = Duration::from_secs(2);

/// Adds `value` to the comma-separated list `key` of `info` unless it is there.
fn list_once(info: &mut BTreeMap<String, String>, key: &str, value: &str) {
    let list = info.remove(key).unwrap_or_default();
    let mut items: Vec<&str> = list.split(", ").filter(|s| !s.is_empty()).collect();
    if !items.contains(&value) {
        items.push(value);
    }
    info.insert(key.to_string(), items.join(", "));
}

/// Where a reference render goes: the film (new or resumed), the file, the progress bar and
/// the live view (`--tev`).
struct Target {
    film: Film,
    out: PathBuf,
    bar: ProgressBar,
    view: Option<LiveView>,
}

/// Renders the reference `spec` names (resuming its film when it names one) and writes it
/// with its PNG preview; a signal stops it with the film written.
pub fn render(mut spec: ReferenceSpec) -> Result<()> {
    let mut run = Run::load_named(&spec.run, "`reference`")?;
    let resume_path = spec.resume.as_ref().map(|(p, _)| p.as_path());
    // After the inputs' checks (their errors first), before any GPU work.
    check_out(&spec.out, spec.force, resume_path)?;
    // One measurement for every GPU and for the film (a resumed film brings its own).
    let first_gpu = match &spec.gpus {
        Some(gpus) => gpu_selectors(gpus)?.into_iter().next(),
        None => spec.run.adapter.clone(),
    };
    run.measure_on(first_gpu.as_deref())?;
    let size = (run.options.width, run.options.height);
    let resumed = spec.resume.take();
    let film = film(&spec, &run, resumed)?;
    run.spec.first_frame = film.next_first_frame(spec.first_frame)? as u64;
    eprintln!(
        "scene {} (loaded in {:.2} s) | graph {} layout {} | {}x{} | {} spp so far",
        spec.run.scene,
        run.scene.load_seconds,
        run.graph.name,
        run.layout,
        size.0,
        size.1,
        film.samples_per_pixel()
    );
    let bar = match (spec.time, spec.frames) {
        (Some(t), _) => ProgressBar::new(t.as_millis() as u64),
        (None, frames) => ProgressBar::new(frames.unwrap_or(0) as u64),
    };
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
    let view = LiveView::open(spec.tev.as_deref(), &spec.out.display().to_string(), size);
    let out = spec.out.clone();
    let before = (film.frames, film.seconds);
    let mut target = Target { film, out, bar, view };
    match &spec.gpus {
        Some(gpus) => on_several_gpus(&spec, &run, gpus, &mut target)?,
        None => on_one_gpu(&spec, &run, &mut target)?,
    }
    let resume = resume_command(&spec, &target.film, before);
    finish(target, spec.exposure, resume)
}

/// The command that goes on with the reference after a signal stopped this run, which began
/// with the film's `(frames, seconds)` at `before`: the frames in all (as `--frames` counts
/// them with `--resume`) or the time left of this run.
fn resume_command(spec: &ReferenceSpec, film: &Film, before: (u64, f64)) -> String {
    let budget = match (spec.time, spec.frames) {
        (Some(t), _) => format!(
            "--time {}s",
            (t.as_secs_f64() - (film.seconds - before.1)).ceil().max(1.0)
        ),
        (None, frames) => format!("--frames {}", before.0 + u64::from(frames.unwrap_or(0))),
    };
    let gpus = spec
        .gpus
        .as_ref()
        .map_or_else(String::new, |g| format!(" --gpus {}", shell_word(Path::new(g))));
    format!("lightgraph reference --resume {} {budget}{gpus}", shell_word(&spec.out))
}

/// The film of the run: the resumed one, checked to have its settings and size, or a new
/// one; with the run's settings and layout.
fn film(spec: &ReferenceSpec, run: &Run, resumed: Option<(PathBuf, Film)>) -> Result<Film> {
    let size = (run.options.width, run.options.height);
    let info = film_settings(&spec.run.scene, &run.graph, &run.options);
    let mut film = match resumed {
        Some((path, r)) => {
            r.check_settings(&info, &path)?;
            r.check_size(&path, size)?;
            r
        }
        None => Film::new(size, info.clone()),
    };
    film.info.extend(info);
    list_once(&mut film.info, "layout", &run.layout);
    Ok(film)
}

/// Writes the target's film and its PNG preview and says so; after a signal, says that the
/// command `resume` goes on.
fn finish(target: Target, exposure: f32, resume: String) -> Result<()> {
    let Target { film, out, bar, view } = target;
    bar.finish();
    if let Some(mut v) = view {
        v.show(&film.mean());
    }
    let png = write_with_preview(&film, &out, "reference", exposure)?;
    println!(
        "wrote {} and {}: {} spp in {:.1} s in all; noise (RMSE of the reference itself) {:.3e}",
        out.display(),
        png.display(),
        film.samples_per_pixel(),
        film.seconds,
        film.noise_floor_mse().sqrt()
    );
    stopped_by_signal(format!(
        "{} holds {} spp; `{resume}` goes on",
        out.display(),
        film.samples_per_pixel(),
    ))
}

/// The progress message: samples per pixel in all and the run's samples per second.
fn progress(film: &Film, spp_before: u64, size: (u32, u32), secs: f64) -> String {
    let spp = film.samples_per_pixel();
    let samples = (spp - spp_before) as f64 * size.0 as f64 * size.1 as f64;
    format!("{spp} spp | {} samples/s", si(samples / secs))
}

/// The reference's observer on one GPU: takes the GPU's sums every [`ABSORB_EVERY`] for the
/// live view and moves the progress bar (the checkpoints are [`Checkpoint`]'s).
struct OneGpu<'a> {
    bar: &'a ProgressBar,
    view: &'a mut Option<LiveView>,
    time: Option<Duration>,
    spp_before: u64,
    absorbed_at: Instant,
}

impl Observer<Filmed<'_, '_>> for OneGpu<'_> {
    fn batch(&mut self, filmed: &mut Filmed, clock: &mut Stopwatch) -> Result<()> {
        if self.absorbed_at.elapsed() >= ABSORB_EVERY {
            filmed.absorb()?;
            self.absorbed_at = Instant::now();
            if let Some(v) = self.view.as_mut().filter(|v| v.due()) {
                v.show(&filmed.film.mean());
            }
        }
        let film = &filmed.film;
        self.bar
            .set_message(progress(film, self.spp_before, film.size, clock.seconds()));
        self.bar.set_position(match self.time {
            Some(_) => clock.elapsed().as_millis() as u64,
            None => filmed.session.frames as u64,
        });
        Ok(())
    }
}

/// Renders `run` on one GPU (`--adapter`) into the target's film through the driver
/// ([`OneGpu`] and the [`Checkpoint`] observing).
fn on_one_gpu(args: &ReferenceSpec, run: &Run, target: &mut Target) -> Result<()> {
    let gpu = Gpu::new(args.run.adapter.as_deref())?;
    eprintln!("{}", gpu.describe());
    list_once(&mut target.film.info, "adapter", &gpu.info.name);
    let mut session = run.session(&gpu)?;
    let Target { film, out, bar, view } = target;
    let mut observer = OneGpu {
        bar,
        view,
        time: args.time,
        spp_before: film.samples_per_pixel(),
        absorbed_at: Instant::now(),
    };
    let mut checkpoint = Checkpoint::new(Some(args.checkpoint), out, "reference", args.exposure);
    let mut filmed = Filmed::new(&mut session, film);
    let plan = Plan::new(budget(args));
    drive(
        &mut filmed,
        plan,
        &mut Stopwatch::start(),
        &mut [&mut checkpoint, &mut observer],
    )?;
    filmed.absorb()
}

/// The budget `--time` or `--frames` (none: no frames) gives.
fn budget(args: &ReferenceSpec) -> Budget {
    match (args.time, args.frames) {
        (Some(t), _) => Budget::Time(t),
        (None, frames) => Budget::Frames(frames.unwrap_or(0) as u64),
    }
}

/// Renders `run` on the GPUs `spec` names (`--gpus`, lightgraph::multi) into the target's
/// film, writing it every `--checkpoint` ([`Checkpoint`]; with the seconds of the runs
/// before this one).
fn on_several_gpus(args: &ReferenceSpec, run: &Run, spec: &str, target: &mut Target) -> Result<()> {
    let selectors = gpu_selectors(spec)?;
    let budget = budget(args);
    let spp_before = target.film.samples_per_pixel();
    let frames_before = target.film.frames;
    let start = Instant::now();
    let (bar, out, view) = (&target.bar, &target.out, &mut target.view);
    let mut checkpoint = Checkpoint::new(Some(args.checkpoint), out, "reference", args.exposure);
    let mut checkpoint_error = None;
    let (shares, _) = render_on_gpus(run, &selectors, budget, &mut target.film, |_, film| {
        if let Some(v) = view.as_mut().filter(|v| v.due()) {
            v.show(&film.mean());
        }
        if let Err(e) = checkpoint.write_if_due(film) {
            checkpoint_error.get_or_insert(e);
        }
        bar.set_message(progress(film, spp_before, film.size, start.elapsed().as_secs_f64()));
        bar.set_position(match args.time {
            Some(_) => start.elapsed().as_millis() as u64,
            None => film.frames - frames_before,
        });
    })?;
    if let Some(e) = checkpoint_error {
        return Err(e);
    }
    for s in &shares {
        list_once(&mut target.film.info, "adapter", &s.adapter);
    }
    target.film.seconds += start.elapsed().as_secs_f64();
    Ok(())
}
