//! `lightgraph render`: a progressive render to EXR and PNG.

use super::args::*;
use anyhow::{Result, bail};
use clap::Args;
use lightgraph::aov::{Aov, AovRender};
use lightgraph::metrics::image_error;
use lightgraph::output;
use lightgraph::reference::{Reference, film_settings};
use lightgraph::render::{LoadedScene, Session, SessionOptions, load_graph, load_scene_with};
use lightgraph::tev::LiveView;
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{Gpu, Graph};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    #[command(flatten)]
    pub tev: TevArg,
    /// Kernel layout (default: the graph's); `auto` measures every legal layout first and
    /// renders with the fastest.
    #[arg(long)]
    pub layout: Option<String>,
    /// Time each layout gets when --layout auto measures it.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "500ms")]
    pub tune_time: Duration,
    /// Render for this long (e.g. 10s, 2m); overrides --frames.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true)]
    pub time: Option<Duration>,
    /// Frames to render.
    #[arg(long, default_value_t = 64, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub frames: u32,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Output EXR; a PNG preview is written beside it.
    #[arg(long, default_value = "out/render.exr")]
    pub out: PathBuf,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// A reference EXR (from `lightgraph reference`): the progress line shows the error
    /// against it, measured about once a second.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Feature buffers to write as further layers of the EXR, comma-separated: albedo, normal,
    /// depth, position (at each sample's first non-specular hit, averaged over the pixel's
    /// samples that hit; see the README). Rendered by kernels of their own after the run.
    #[arg(long, value_name = "LIST")]
    pub aov: Option<String>,
    /// Frame index of the first frame: renders frames FIRST .. FIRST + frames of the seed's
    /// random streams, a shard of a longer run (`lightgraph merge` adds the shards' films).
    #[arg(long, default_value_t = 0)]
    pub first_frame: u32,
    /// Render on several GPUs at once: `all`, the first N adapters, or a comma-separated list
    /// of adapter indices, PCI bus ids or names (see `lightgraph list`; one may repeat). Each
    /// GPU claims batches of frames sized to its own speed; the host adds them into one film
    /// (`--adapter` is then not used).
    #[arg(long)]
    pub gpus: Option<String>,
    /// Render across the ranks of an MPI job (`mpirun -n N lightgraph render --mpi ...`), one
    /// GPU per rank (the rank's index on its machine, or --adapter); rank 0 writes the film.
    #[cfg(feature = "mpi")]
    #[arg(long, conflicts_with = "gpus")]
    pub mpi: bool,
}

/// `lightgraph render`: sets the session up, renders progressively, writes the film and the
/// PNG, and reports the rates.
pub fn render(args: RenderArgs) -> Result<()> {
    if args.aov.is_some() && (args.gpus.is_some() || mpi_asked(&args)) {
        bail!("--aov renders its buffers on one GPU: leave out --gpus and --mpi");
    }
    #[cfg(feature = "mpi")]
    if args.mpi {
        return super::mpi::render_with_mpi(&args);
    }
    if let Some(spec) = &args.gpus {
        return super::gpus::render_on_several_gpus(&args, spec);
    }
    let c = &args.common;
    let graph = load_graph(args.graph.name())?;
    // A named layout chooses the BVH; `--layout auto` measures its layouts on one.
    let named = match args.layout.as_deref() {
        Some("auto") => None,
        name => Some(named_layout(&graph, name)?),
    };
    let kind = match &named {
        Some((name, decl)) => c.bvh.for_layout(name, decl)?,
        None => c.bvh.or_default(),
    };
    let scene = load_scene_with(c.scene(), kind)?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    let mut opts = options(c, &scene, &graph, args.seed)?;
    let (layout, decl) = match named {
        Some(named) => named,
        None => tune_layout(&gpu, &graph, &scene, &opts, &args)?,
    };
    // Measured once, so that the film records the value (shards must share it to merge).
    let measured = lightgraph::render::measure_constants(&gpu, &graph, &layout, decl.clone(), &scene, &opts)?;
    opts.constants.extend(measured);
    let (w, h) = (opts.width, opts.height);
    eprintln!(
        "{} | scene {} ({} primitives, {} lights, loaded in {:.2} s) | graph {} layout {} | {w}x{h}",
        gpu.describe(),
        c.scene(),
        scene.compiled.primitives.len(),
        scene.compiled.lights.len(),
        scene.load_seconds,
        graph.name,
        layout
    );
    let reference = reference_mean(args.reference.as_ref(), (w, h))?;
    let mut film = Reference::new((w, h), film_settings(c.scene(), &graph, &opts));
    let mut session = Session::with_layout(&gpu, &graph, &layout, decl, &scene, opts)?;
    session.first_frame = args.first_frame;
    // A frame count that splits a group of frames rendered at once is refused before rendering.
    session.check_frames(args.first_frame, if args.time.is_none() { args.frames } else { 0 })?;
    let mut view = args.tev.view(&args.out.display().to_string(), (w, h));
    let seconds = render_progressively(&mut session, &args, reference.as_deref(), &mut view)?;
    let image = session.image()?;
    if let Some(v) = &mut view {
        v.show(&image.mean);
    }
    if let Some(r) = &reference {
        let e = image_error(&image.mean, r);
        eprintln!(
            "error against {}: RMSE {:.4e}, relMSE {:.4e}",
            args.reference.as_ref().expect("a reference path").display(),
            e.rmse,
            e.rel_mse
        );
    }
    let rejected = rejected_samples(&session);
    for (k, v) in [
        ("layout", layout.clone()),
        ("adapter", gpu.info.name.clone()),
        ("rays", session.rays().to_string()),
        ("rejected_samples", rejected.to_string()),
    ] {
        film.info.insert(k.to_string(), v);
    }
    film.absorb(&session.accumulation()?)?;
    film.seconds = seconds;
    if let Some(list) = &args.aov {
        film.layers = feature_buffers(&gpu, &scene, &session, list, args.first_frame)?;
    }
    film.write(&args.out, "render")?;
    let png = args.out.with_extension("png");
    output::write_png(&png, &image, args.exposure)?;
    report_rates(&session, seconds);
    println!("wrote {} and {}", args.out.display(), png.display());
    Ok(())
}

/// Renders `session` for `--time` or `--frames`, with a progress bar of samples/s, rays/s and,
/// against `reference`, the RMSE (once a second), and the live view; returns the seconds taken.
fn render_progressively(
    session: &mut Session,
    args: &RenderArgs,
    reference: Option<&[[f32; 3]]>,
    view: &mut Option<LiveView>,
) -> Result<f64> {
    let (w, h) = (session.options.width as f64, session.options.height as f64);
    let mut error_text = String::new();
    let mut error_at: Option<Instant> = None;
    let bar = super::gpus::progress_bar(args);
    let start = Instant::now();
    loop {
        let elapsed = start.elapsed();
        let done = match args.time {
            Some(t) => elapsed >= t,
            None => session.frames >= args.frames,
        };
        if done {
            break;
        }
        match args.time {
            Some(t) => session.render_for(Some(t.saturating_sub(elapsed)), u32::MAX)?,
            None => session.render_for(None, args.frames - session.frames)?,
        };
        // Rates of the frames read back (one batch may still be running).
        let secs = start.elapsed().as_secs_f64();
        let samples = session.settled as f64 * session.options.samples_per_frame as f64 * w * h;
        if let Some(r) = reference
            && error_at.is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            error_text = format!(" | RMSE {:.4e}", image_error(&session.image()?.mean, r).rmse);
            error_at = Some(Instant::now());
        }
        if let Some(v) = view.as_mut().filter(|v| v.due()) {
            v.show(&session.image()?.mean);
        }
        bar.set_message(format!(
            "frame {} | {} samples/s | {}rays/s{error_text}",
            session.frames,
            si(samples / secs),
            si(session.rays() as f64 / secs)
        ));
        match args.time {
            Some(_) => bar.set_position(start.elapsed().as_millis() as u64),
            None => bar.set_position(session.frames as u64),
        }
    }
    session.settle()?;
    bar.finish();
    Ok(start.elapsed().as_secs_f64())
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

/// `--layout auto`: measures every legal layout of `graph`, writes the table beside the
/// output, and returns the fastest.
fn tune_layout(
    gpu: &Gpu,
    graph: &Graph,
    scene: &LoadedScene,
    opts: &SessionOptions,
    args: &RenderArgs,
) -> Result<(String, LayoutDecl)> {
    eprintln!(
        "--layout auto: measuring every legal layout of '{}' for {:?} each",
        graph.name, args.tune_time
    );
    let trials = lightgraph::tune::autotune(gpu, graph, scene, opts, args.tune_time, |t| {
        eprintln!("  {:>9.1} Msamples/s  {}", t.score() / 1e6, t.name);
    })?;
    let table = lightgraph::tune::table(&trials);
    println!("{table}");
    let report = args.out.with_extension("auto.md");
    if let Some(dir) = report.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&report, &table)?;
    let best = &trials[0];
    eprintln!(
        "winner: {} ({:.1} Msamples/s); table in {}",
        best.name,
        best.score() / 1e6,
        report.display()
    );
    Ok((best.name.clone(), best.decl.clone()))
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
