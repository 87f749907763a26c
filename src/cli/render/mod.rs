//! `lightgraph render`: a progressive render to EXR and PNG, on one GPU, several (`--gpus`,
//! [`gpus`]) or the ranks of an MPI job (`--mpi`, [`mpi`]); `--layout auto` ([`auto`]).

mod auto;
mod gpus;
pub mod html;
#[cfg(feature = "mpi")]
mod mpi;

use super::args::*;
use super::film::{FilmArgs, FilmDefaults};
use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::aov::{Aov, AovRender};
use lightgraph::checkpoint::{Checkpoint, Filmed, write_with_preview};
use lightgraph::compare::ErrorSample;
use lightgraph::drive::{Observer, Plan, Stopwatch, drive};
use lightgraph::film::{Film, film_settings};
use lightgraph::interrupt;
use lightgraph::interrupt::stopped_by_signal;
use lightgraph::live::Live;
use lightgraph::metrics::image_error;
use lightgraph::output;
use lightgraph::output::{check_out, shell_word};
use lightgraph::run::{LoadedScene, Run, RunSpec, Session};
use lightgraph::serve::LiveServer;
use lightgraph_engine::Gpu;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    #[command(flatten)]
    pub tev: TevArg,
    #[command(flatten)]
    pub film: FilmArgs,
    /// Time each layout gets when --layout auto refines it (half of it to screen each legal
    /// layout).
    #[arg(long, value_parser = crate::cli::checks::duration, allow_hyphen_values = true, default_value = "300ms")]
    pub tune_time: Duration,
    /// With --layout auto: measure again even where the layout cache holds this render's
    /// fastest layout (and store the new winner).
    #[arg(long)]
    pub retune: bool,
    /// A reference EXR (from `lightgraph reference`): the progress line shows the error
    /// against it, measured about once a second.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Feature buffers to write as further layers of the EXR, comma-separated: albedo, normal,
    /// depth, position (at each sample's first non-specular hit, averaged over the pixel's
    /// samples that hit; see docs/usage.md). Rendered by kernels of their own after the run.
    #[arg(long, value_name = "LIST")]
    pub aov: Option<String>,
    /// Render across the ranks of an MPI job (`mpirun -n N lightgraph render --mpi ...`), one
    /// GPU per rank (the rank's index on its machine, or --adapter); rank 0 writes the film.
    #[cfg(feature = "mpi")]
    #[arg(long, conflicts_with = "gpus")]
    pub mpi: bool,
    /// Serve the progressive film to a browser at HOST:PORT [default: 127.0.0.1:8731]: the
    /// report viewer, updated as frames land, with samples/s and the error against
    /// --reference. On a remote machine, watch it through `ssh -L 8731:127.0.0.1:8731 HOST`.
    #[arg(long, num_args = 0..=1, default_missing_value = lightgraph::serve::DEFAULT_ADDRESS, value_name = "HOST:PORT")]
    pub serve: Option<String>,
}

/// What a render's film defaults to: seed 1, out/render.exr, no checkpoints.
pub const RENDER: FilmDefaults = FilmDefaults {
    seed: 1,
    out: "out/render.exr",
    checkpoint: None,
};

impl RenderArgs {
    /// The film's path: --out, else the resumed film, else out/render.exr.
    pub fn out(&self) -> PathBuf {
        self.film.out(&RENDER)
    }

    /// Checks the film's path (see [`check_out`]) and, with --reference, its HTML report's
    /// (replaced with --force or when resuming the film).
    pub fn check_out(&self) -> Result<()> {
        let out = self.out();
        let film = &self.film;
        check_out(&out, film.force, film.resume.as_deref())?;
        match self.reference {
            Some(_) => output::check_outputs(
                &[output::Output::File(&html::html_path(&out))],
                film.force || film.resume.is_some(),
                None,
            ),
            None => Ok(()),
        }
    }

    /// The live views asked for (--tev, --serve) of the film `out` of `size` pixels, with the
    /// reference if any; the server is listening when this returns.
    pub fn live(&self, out: &Path, size: (u32, u32), reference: Option<&[[f32; 3]]>) -> Result<Live> {
        let name = out.display().to_string();
        let server = match &self.serve {
            Some(address) => {
                let server = LiveServer::start(address, &name, size, reference)?;
                eprintln!("live view at {}", server.url());
                Some(server)
            }
            None => None,
        };
        Ok(Live {
            tev: self.tev.view(&name, size),
            server,
        })
    }

    /// The command that goes on with the film at `out` after a signal stopped this run once
    /// it rendered for `seconds`: the same frames in all, or the time left; `extra` adds
    /// options (` --gpus 2`).
    pub fn resume_command(&self, out: &Path, seconds: f64, extra: &str) -> String {
        let budget = match self.film.time {
            Some(t) => format!("--time {}s", (t.as_secs_f64() - seconds).ceil().max(1.0)),
            None => format!("--frames {}", self.film.frames()),
        };
        format!("lightgraph render --resume {} {budget}{extra}", shell_word(out))
    }

    /// The run these arguments name.
    pub fn spec(&self) -> RunSpec {
        let film = &self.film;
        RunSpec {
            first_frame: film.first_frame() as u64,
            ..self
                .common
                .spec(self.graph.name(), film.layout.as_deref(), film.seed(&RENDER))
        }
    }

    /// The film `run` starts from: the resumed one (its settings checked against the run's,
    /// measured constants included) or an empty one.
    pub fn start_film(&self, run: &Run, resumed: Option<Film>) -> Result<Film> {
        let opts = &run.options;
        let info = film_settings(&run.spec.scene, &run.graph, opts);
        let size = (opts.width, opts.height);
        match (resumed, &self.film.resume) {
            (Some(film), Some(path)) => {
                film.check_settings(&info, path)?;
                film.check_size(path, size)?;
                Ok(film)
            }
            _ => Ok(Film::new(size, info)),
        }
    }
}

/// Reads the film `--resume` names ([`FilmArgs::resume`]), refusing first what a resumed
/// render cannot do.
fn resume_film(args: &mut RenderArgs) -> Result<Option<Film>> {
    if args.film.resume.is_some() {
        if args.aov.is_some() {
            bail!("--aov renders its buffers over one invocation's frames: leave it out with --resume");
        }
        if args.film.layout.as_deref() == Some("auto") {
            bail!("--layout auto measures layouts before a run: name the film's layout with --resume");
        }
    }
    args.film.resume(&mut args.common, &mut args.graph, &RENDER)
}

/// `lightgraph render`: sets the session up, renders progressively, writes the film and the
/// PNG, and reports the rates. A signal (SIGINT, SIGTERM) ends the run after the frames in
/// flight, with the film written.
pub fn render(mut args: RenderArgs) -> Result<()> {
    if args.aov.is_some() && (args.film.gpus.is_some() || mpi_asked(&args)) {
        bail!("--aov renders its buffers on one GPU: leave out --gpus and --mpi");
    }
    let resumed = resume_film(&mut args)?;
    #[cfg(feature = "mpi")]
    if args.mpi {
        return mpi::render_with_mpi(&args, resumed);
    }
    if let Some(spec) = &args.film.gpus {
        return gpus::render_on_several_gpus(&args, spec, resumed);
    }
    let mut run = Run::load(&args.spec())?;
    // The output is checked (after the inputs, whose errors come first) before the device opens.
    args.check_out()?;
    let gpu = Gpu::new(run.spec.adapter.as_deref())?;
    if !auto::choose_layout(&gpu, &mut run, &args)? && args.film.layout.is_none() {
        auto::take_measured_default(&gpu, &mut run)?;
    }
    // Measured once, so that the film records the value (shards must share it to merge).
    run.measure(&gpu)?;
    let (w, h) = (run.options.width, run.options.height);
    eprintln!(
        "{} | scene {} ({}) | graph {} layout {} | {w}x{h}",
        gpu.describe(),
        run.spec.scene,
        scene_size(&run.scene),
        run.graph.name,
        run.layout
    );
    let reference = reference_mean(args.reference.as_ref(), (w, h))?;
    let mut film = args.start_film(&run, resumed)?;
    for (k, v) in [("layout", run.layout.clone()), ("adapter", gpu.info.name.clone())] {
        film.info.insert(k.to_string(), v);
    }
    let mut session = run.session(&gpu)?;
    // A frame count that splits a group of frames rendered at once is refused before rendering.
    let frames = if args.film.time.is_none() {
        args.film.frames_left
    } else {
        0
    };
    session.check_frames(args.film.first_frame(), frames)?;
    let out = args.out();
    let mut view = args.live(&out, (w, h), reference.as_deref())?;
    let seconds_before = film.seconds;
    let mut progress = Progress {
        reference: reference.as_deref(),
        errors: Vec::new(),
        view: &mut view,
        args: &args,
        bar: progress_bar(&args),
        error_text: String::new(),
        error_at: None,
    };
    let last_line = render_progressively(&mut Filmed::new(&mut session, &mut film), &out, &mut progress)?;
    let mut errors = std::mem::take(&mut progress.errors);
    view.show(&film.mean(), film.frames, &format!("{last_line} | finished"), true);
    if let Some(r) = &reference {
        let e = image_error(&film.mean(), r);
        eprintln!(
            "error against {}: RMSE {:.4e}, relMSE {:.4e}",
            args.reference.as_ref().expect("a reference path").display(),
            e.rmse,
            e.rel_mse
        );
        errors.push(ErrorSample {
            seconds: film.seconds - seconds_before,
            frames: session.frames,
            samples_per_pixel: session.samples_per_pixel(),
            error: e,
        });
    }
    add_statistics(&mut film, &session);
    if let Some(list) = &args.aov {
        film.layers = feature_buffers(&gpu, &run.scene, &session, list, args.film.first_frame())?;
    }
    let png = write_film(&film, &out, args.film.exposure)?;
    let seconds = film.seconds - seconds_before;
    report_rates(&session, seconds);
    println!("wrote {} and {}", out.display(), png.display());
    if let Some(path) = &args.reference {
        html::write_html(&out, &film, (path, &run.layout), &errors)?;
        println!("wrote {} (opens offline in a browser)", html::html_path(&out).display());
    }
    stopped_by_signal(format!(
        "{} and {} hold {} frames; `{}` goes on",
        out.display(),
        png.display(),
        film.frames,
        args.resume_command(&out, seconds, "")
    ))
}

/// Adds the session's rays and rejected samples to the film's (a resumed film's count on).
fn add_statistics(film: &mut Film, session: &Session) {
    for (key, value) in [
        ("rays", session.rays()),
        ("rejected_samples", rejected_samples(session)),
    ] {
        let before = film.info.get(key).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
        film.info.insert(key.to_string(), (before + value).to_string());
    }
}

/// Writes `film` to `out` and its PNG preview beside it; returns the PNG's path.
pub fn write_film(film: &Film, out: &Path, exposure: f32) -> Result<PathBuf> {
    write_with_preview(film, out, "render", exposure)
}

/// What a progressive render shows while it runs: as the driver's observer it samples the
/// error against the reference, moves the progress bar and feeds the live view after every
/// batch (the checkpoints are [`Checkpoint`]'s).
struct Progress<'a> {
    reference: Option<&'a [[f32; 3]]>,
    /// The error against the reference, about once a second.
    errors: Vec<ErrorSample>,
    view: &'a mut Live,
    args: &'a RenderArgs,
    bar: ProgressBar,
    error_text: String,
    error_at: Option<Instant>,
}

impl Observer<Filmed<'_, '_>> for Progress<'_> {
    fn batch(&mut self, filmed: &mut Filmed, clock: &mut Stopwatch) -> Result<()> {
        let session = &*filmed.session;
        // Rates of the frames read back (one batch may still be running).
        let secs = clock.seconds();
        let (w, h) = (session.options.width as f64, session.options.height as f64);
        let samples = session.settled as f64 * session.options.samples_per_frame as f64 * w * h;
        if let Some(r) = self.reference
            && self.error_at.is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            let error = image_error(&filmed.mean()?, r);
            self.error_text = format!(" | RMSE {:.4e}", error.rmse);
            self.error_at = Some(Instant::now());
            self.errors.push(ErrorSample {
                seconds: secs,
                frames: session.settled,
                samples_per_pixel: session.samples_per_pixel(),
                error,
            });
        }
        self.bar.set_message(format!(
            "frame {} | {} samples/s | {}rays/s{}",
            session.frames,
            si(samples / secs),
            si(session.rays() as f64 / secs),
            self.error_text
        ));
        if self.view.due() {
            let mean = filmed.mean()?;
            self.view
                .show(&mean, filmed.frames_in_all(), &self.bar.message(), false);
        }
        match self.args.film.time {
            Some(_) => self.bar.set_position(clock.elapsed().as_millis() as u64),
            None => self.bar.set_position(session.frames as u64),
        }
        Ok(())
    }
}

/// Renders `filmed`'s session for `--time` or `--frames` into its film through the driver,
/// with a progress bar of samples/s, rays/s and, against a reference, the RMSE (once a
/// second), and the live view; writes the film to `out` every `--checkpoint`. Stops early,
/// after the frames in flight, when a signal arrives. Returns the last progress line.
fn render_progressively(filmed: &mut Filmed, out: &Path, progress: &mut Progress) -> Result<String> {
    let film = &progress.args.film;
    let mut checkpoint = Checkpoint::new(film.checkpoint(&RENDER), out, "render", film.exposure);
    let mut clock = Stopwatch::start();
    drive(
        filmed,
        Plan::new(film.budget()),
        &mut clock,
        &mut [&mut checkpoint, &mut *progress],
    )?;
    progress.bar.finish();
    filmed.absorb()?;
    if let Some(signal) = interrupt::requested() {
        eprintln!(
            "{} received: stopped after frame {}, writing the film",
            signal.name(),
            filmed.film.end_frame()
        );
    }
    Ok(progress.bar.message())
}

/// The samples the session's kernels rejected (non-finite or negative).
fn rejected_samples(session: &Session) -> u64 {
    session.counters.get("samples_rejected").copied().unwrap_or(0)
}

/// The render's rates on stderr: samples/s and rays/s wall-clock and of GPU time, the counters
/// and each kernel's GPU time per frame, and loops that hit their iteration cap.
fn report_rates(session: &Session, seconds: f64) {
    let rejected = rejected_samples(session);
    let gpu_time: f64 = session.kernel_seconds.values().sum();
    let frames = session.frames.max(1) as f64;
    let pixels = (session.options.width * session.options.height) as f64;
    let samples = session.samples_per_pixel() as f64 * pixels;
    eprintln!(
        "{} frames, {} spp in {seconds:.2} s: {}samples/s, {}rays/s wall-clock; GPU kernel time {gpu_time:.3} s ({}rays/s); {rejected} rejected samples",
        session.frames,
        session.samples_per_pixel(),
        si(samples / seconds),
        si(session.rays() as f64 / seconds),
        si(session.rays() as f64 / gpu_time.max(1e-12)),
    );
    let counters: Vec<String> = session
        .counters
        .iter()
        .map(|(k, v)| format!("{k} {}", si(*v as f64 / frames)))
        .collect();
    eprintln!("per frame: {}", counters.join(", "));
    let kernels: Vec<String> = session
        .kernel_seconds
        .iter()
        .map(|(k, v)| format!("{k} {:.3} ms", 1e3 * v / frames))
        .collect();
    if !kernels.is_empty() {
        eprintln!("GPU time per frame: {}", kernels.join(", "));
    }
    if session.loops_capped > 0 {
        eprintln!(
            "warning: {} loops hit the iteration cap (a pass that never finished its item)",
            session.loops_capped
        );
    }
}

/// The feature buffers `list` names, over the frames `session` rendered (see lightgraph::aov).
fn feature_buffers(
    gpu: &Gpu,
    scene: &LoadedScene,
    session: &Session,
    list: &str,
    first_frame: u32,
) -> Result<Vec<(String, Vec<f32>)>> {
    let aovs = Aov::parse_list(list)?;
    let started = Instant::now();
    let mut render = AovRender::new(gpu, scene, &session.options, &aovs)?;
    render.render(first_frame, session.frames)?;
    let layers = render.layers()?;
    let names: Vec<&str> = aovs.iter().map(|a| a.name()).collect();
    eprintln!(
        "feature buffers {} over {} frames in {:.2} s",
        names.join(", "),
        session.frames,
        started.elapsed().as_secs_f64()
    );
    Ok(layers)
}

/// Whether `args` asks for an MPI run.
#[cfg(feature = "mpi")]
fn mpi_asked(args: &RenderArgs) -> bool {
    args.mpi
}

/// Whether `args` asks for an MPI run (never without the `mpi` feature).
#[cfg(not(feature = "mpi"))]
fn mpi_asked(_: &RenderArgs) -> bool {
    false
}

/// The scene's size and load time: primitives, lights, seconds to load, the BVH's build time
/// and rate, and the geometry's bytes on the GPU, in all and a primitive.
fn scene_size(scene: &LoadedScene) -> String {
    let c = &scene.compiled;
    let n = c.primitives.len().max(1) as f64;
    let build = c.bvh_time.as_secs_f64();
    format!(
        "{} primitives, {} lights, loaded in {:.2} s, BVH built in {:.2} s ({:.2} M primitives/s), geometry {:.1} MiB ({:.0} bytes a primitive)",
        c.primitives.len(),
        c.lights.len(),
        scene.load_seconds,
        build,
        n / build.max(1e-9) / 1e6,
        c.geometry_bytes() as f64 / 1048576.0,
        c.geometry_bytes() as f64 / n,
    )
}

/// The progress bar of a render of `args`: over its time in milliseconds, else its frames.
fn progress_bar(args: &RenderArgs) -> ProgressBar {
    let film = &args.film;
    let bar = ProgressBar::new(film.time.map_or(film.frames_left as u64, |t| t.as_millis() as u64));
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
    bar
}
