//! `lightgraph reference`: a long render accumulated in f64 on the host, with its variance,
//! written as a reference EXR and resumable.

use super::args::*;
use super::film::{check_out, settings_from_film, stopped_by_signal};
use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::multi::{Budget, gpu_selectors, render_on_gpus};
use lightgraph::reference::{Reference, film_settings};
use lightgraph::run::Run;
use lightgraph::tev::LiveView;
use lightgraph_engine::Gpu;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The default seed of references: not the default of `render` and `compare` (1), so runs
/// compared with a reference draw other random numbers than it did.
pub const REFERENCE_SEED: u32 = 1_000_003;

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    #[command(flatten)]
    pub tev: TevArg,
    /// Kernel layout (default: the graph's); every layout of a graph gives the same image.
    #[arg(long)]
    pub layout: Option<String>,
    /// Render for this long (added to what a resumed reference has).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, required_unless_present = "frames")]
    pub time: Option<Duration>,
    /// Render this many frames instead (for reproducible references and tests).
    #[arg(long, conflicts_with = "time", value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Seed of the random streams [default: 1000003, or the resumed reference's].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Add samples to this reference; scene, graph, resolution, samples per frame, seed and
    /// constants default to its own, and must match when given.
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Output EXR [default: the resumed file, else out/reference.exr]; a PNG preview is
    /// written beside it.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing --out (without it, an existing file is refused unless --resume
    /// names it).
    #[arg(long)]
    pub force: bool,
    /// Write the reference every this often while rendering, so a long run that is stopped
    /// keeps its samples.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "5m")]
    pub checkpoint: Duration,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Frame index of the first frame [default: 0, or where the resumed reference ends]: the
    /// shard of one run that this process renders (`merge` adds the shards up).
    #[arg(long)]
    pub first_frame: Option<u32>,
    /// Render on several GPUs at once, as `render --gpus`: `all`, the first N adapters, or a
    /// comma-separated list of adapter indices, PCI bus ids or names (`--adapter` is then
    /// not used).
    #[arg(long)]
    pub gpus: Option<String>,
}

/// The first frame index of this run: `given`, which must come after every frame the
/// (resumed) film holds, or the end of those frames.
fn first_frame(given: Option<u32>, film: &Reference) -> Result<u32> {
    let end = film.end_frame();
    let first = given.map_or(end, u64::from);
    if first < end {
        bail!("--first-frame {first} is inside the frames the reference holds (up to {end}); give {end} or more");
    }
    u32::try_from(first)
        .map_err(|_| anyhow::anyhow!("the reference ends at frame {end}, past 2^32; start another with a new seed"))
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
    film: Reference,
    out: PathBuf,
    bar: ProgressBar,
    view: Option<LiveView>,
}

pub fn reference(mut args: ReferenceArgs) -> Result<()> {
    let resumed = match &args.resume {
        Some(path) => Some(Reference::read(path)?),
        None => None,
    };
    if let Some(r) = &resumed {
        let (common, graph, seed) = (&mut args.common, &mut args.graph, &mut args.seed);
        settings_from_film(common, graph, seed, REFERENCE_SEED, r);
    }
    let c = &args.common;
    let out = match (&args.out, &args.resume) {
        (Some(o), _) => o.clone(),
        (None, Some(r)) => r.clone(),
        (None, None) => PathBuf::from("out/reference.exr"),
    };
    let seed = args.seed.unwrap_or(REFERENCE_SEED);
    let mut run = Run::load_named(&c.spec(args.graph.name(), args.layout.as_deref(), seed), "`reference`")?;
    // After the inputs' checks (their errors first), before any GPU work.
    check_out(&out, args.force, args.resume.as_deref())?;
    // One measurement for every GPU and for the film (a resumed film brings its own).
    let first_gpu = match &args.gpus {
        Some(spec) => gpu_selectors(spec)?.into_iter().next(),
        None => c.adapter.clone(),
    };
    run.measure_on(first_gpu.as_deref())?;
    let size = (run.options.width, run.options.height);
    let info = film_settings(c.scene(), &run.graph, &run.options);
    let mut film = match resumed {
        Some(r) => {
            let path = args.resume.as_ref().expect("resumed from a path");
            r.check_settings(&info, path)?;
            check_size(&r, path, size)?;
            r
        }
        None => Reference::new(size, info.clone()),
    };
    film.info.extend(info);
    list_once(&mut film.info, "layout", &run.layout);
    run.spec.first_frame = first_frame(args.first_frame, &film)? as u64;
    eprintln!(
        "scene {} (loaded in {:.2} s) | graph {} layout {} | {}x{} | {} spp so far",
        c.scene(),
        run.scene.load_seconds,
        run.graph.name,
        run.layout,
        size.0,
        size.1,
        film.samples_per_pixel()
    );
    let bar = match (args.time, args.frames) {
        (Some(t), _) => ProgressBar::new(t.as_millis() as u64),
        (None, frames) => ProgressBar::new(frames.unwrap_or(0) as u64),
    };
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
    let view = args.tev.view(&out.display().to_string(), size);
    let mut target = Target { film, out, bar, view };
    match &args.gpus {
        Some(spec) => on_several_gpus(&args, &run, spec, &mut target)?,
        None => on_one_gpu(&args, &run, &mut target)?,
    }
    let Target { film, out, bar, view } = target;
    bar.finish();
    if let Some(mut v) = view {
        v.show(&film.mean());
    }
    film.write(&out, "reference")?;
    let png = out.with_extension("png");
    lightgraph::output::write_png(&png, &film.image(), args.exposure)?;
    println!(
        "wrote {} and {}: {} spp in {:.1} s in all; noise (RMSE of the reference itself) {:.3e}",
        out.display(),
        png.display(),
        film.samples_per_pixel(),
        film.seconds,
        film.noise_floor_mse().sqrt()
    );
    stopped_by_signal(format!(
        "{} holds {} spp; `lightgraph reference --resume {}` goes on",
        out.display(),
        film.samples_per_pixel(),
        out.display()
    ))
}

/// The progress message: samples per pixel in all and the run's samples per second.
fn progress(film: &Reference, spp_before: u64, size: (u32, u32), secs: f64) -> String {
    let spp = film.samples_per_pixel();
    let samples = (spp - spp_before) as f64 * size.0 as f64 * size.1 as f64;
    format!("{spp} spp | {} samples/s", si(samples / secs))
}

/// Renders `run` on one GPU (`--adapter`) into the target's film, taking the GPU's sums
/// every [`ABSORB_EVERY`] and writing the film every `--checkpoint`.
fn on_one_gpu(args: &ReferenceArgs, run: &Run, target: &mut Target) -> Result<()> {
    let gpu = Gpu::new(args.common.adapter.as_deref())?;
    eprintln!("{}", gpu.describe());
    let film = &mut target.film;
    list_once(&mut film.info, "adapter", &gpu.info.name);
    let mut session = run.session(&gpu)?;
    let spp_before = film.samples_per_pixel();
    let start = Instant::now();
    let (mut absorbed_at, mut saved_at) = (Instant::now(), Instant::now());
    let mut seconds_saved = 0.0;
    loop {
        let (left, max) = match (args.time, args.frames) {
            (Some(t), _) => (Some(t.saturating_sub(start.elapsed())), u32::MAX),
            (None, frames) => (None, frames.unwrap_or(0).saturating_sub(session.frames)),
        };
        if left.is_some_and(|l| l.is_zero()) || max == 0 || lightgraph::interrupt::requested().is_some() {
            break;
        }
        session.render_for(left, max)?;
        if absorbed_at.elapsed() >= ABSORB_EVERY || saved_at.elapsed() >= args.checkpoint {
            film.absorb(&session.take_accumulation()?)?;
            absorbed_at = Instant::now();
            if let Some(v) = target.view.as_mut().filter(|v| v.due()) {
                v.show(&film.mean());
            }
        }
        if saved_at.elapsed() >= args.checkpoint {
            let now = start.elapsed().as_secs_f64();
            film.seconds += now - seconds_saved;
            seconds_saved = now;
            film.write(&target.out, "reference")?;
            saved_at = Instant::now();
        }
        target
            .bar
            .set_message(progress(film, spp_before, film.size, start.elapsed().as_secs_f64()));
        target.bar.set_position(match args.time {
            Some(_) => start.elapsed().as_millis() as u64,
            None => session.frames as u64,
        });
    }
    film.absorb(&session.take_accumulation()?)?;
    film.seconds += start.elapsed().as_secs_f64() - seconds_saved;
    Ok(())
}

/// Renders `run` on the GPUs `spec` names (`--gpus`, lightgraph::multi) into the target's
/// film, writing it every `--checkpoint` (with the seconds of the runs before this one).
fn on_several_gpus(args: &ReferenceArgs, run: &Run, spec: &str, target: &mut Target) -> Result<()> {
    let selectors = gpu_selectors(spec)?;
    let budget = match (args.time, args.frames) {
        (Some(t), _) => Budget::Time(t),
        (None, frames) => Budget::Frames(frames.unwrap_or(0) as u64),
    };
    let spp_before = target.film.samples_per_pixel();
    let frames_before = target.film.frames;
    let start = Instant::now();
    let mut saved_at = Instant::now();
    let (bar, out, view) = (&target.bar, &target.out, &mut target.view);
    let mut checkpoint_error = None;
    let (shares, _) = render_on_gpus(run, &selectors, budget, &mut target.film, |_, film| {
        if let Some(v) = view.as_mut().filter(|v| v.due()) {
            v.show(&film.mean());
        }
        if saved_at.elapsed() >= args.checkpoint {
            if let Err(e) = film.write(out, "reference") {
                checkpoint_error.get_or_insert(e);
            }
            saved_at = Instant::now();
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
