//! `lightgraph reference`: a long render accumulated in f64 on the host, with its variance,
//! written as a reference EXR and resumable.

use super::args::*;
use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::reference::Reference;
use lightgraph::render::{Session, load_graph, load_scene_with};
use lightgraph_engine::Gpu;
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
    /// Kernel layout (default: the graph's); every layout of a graph gives the same image.
    #[arg(long)]
    pub layout: Option<String>,
    /// Render for this long (added to what a resumed reference has).
    #[arg(long, value_parser = humantime::parse_duration, required_unless_present = "frames")]
    pub time: Option<Duration>,
    /// Render this many frames instead (for reproducible references and tests).
    #[arg(long, conflicts_with = "time")]
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
    /// Write the reference every this often while rendering, so a long run that is stopped
    /// keeps its samples.
    #[arg(long, value_parser = humantime::parse_duration, default_value = "5m")]
    pub checkpoint: Duration,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Frame index of the first frame [default: 0, or where the resumed reference ends]: the
    /// shard of one run that this process renders (`merge` adds the shards up).
    #[arg(long)]
    pub first_frame: Option<u32>,
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

pub fn reference(mut args: ReferenceArgs) -> Result<()> {
    let resumed = match &args.resume {
        Some(path) => Some(Reference::read(path)?),
        None => None,
    };
    if let Some(r) = &resumed {
        // Settings not given are the reference's own.
        let c = &mut args.common;
        let info = |k: &str| r.info.get(k).cloned().unwrap_or_default();
        c.scene.get_or_insert_with(|| info("scene"));
        args.graph.graph.get_or_insert_with(|| info("graph"));
        c.res.get_or_insert(r.size);
        c.spp
            .get_or_insert_with(|| info("samples_per_frame").parse().unwrap_or(1));
        args.seed
            .get_or_insert_with(|| info("seed").parse().unwrap_or(REFERENCE_SEED));
        if c.set.is_empty() && c.max_path_length.is_none() {
            c.set = info("constants").split_whitespace().map(String::from).collect();
        }
    }
    let c = &args.common;
    let out = match (&args.out, &args.resume) {
        (Some(o), _) => o.clone(),
        (None, Some(r)) => r.clone(),
        (None, None) => PathBuf::from("out/reference.exr"),
    };
    let scene = load_scene_with(c.scene(), c.bvh)?;
    let graph = load_graph(args.graph.name())?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    let seed = args.seed.unwrap_or(REFERENCE_SEED);
    let opts = options(c, &scene, &graph.constants, seed)?;
    let (layout, decl) = named_layout(&graph, args.layout.as_deref())?;
    let size = (opts.width, opts.height);
    let mut info = film_settings(c.scene(), args.graph.name(), &opts);
    let mut reference = match resumed {
        Some(r) => {
            let path = args.resume.as_ref().expect("resumed from a path");
            r.check_settings(&info, path)?;
            check_size(&r, path, size)?;
            r
        }
        None => Reference::new(size, info.clone()),
    };
    // Layouts and adapters that contributed are listed, each once.
    for (key, value) in [("layout", layout.clone()), ("adapter", gpu.info.name.clone())] {
        let list = reference.info.remove(key).unwrap_or_default();
        let mut items: Vec<String> = list.split(", ").filter(|s| !s.is_empty()).map(String::from).collect();
        if !items.contains(&value) {
            items.push(value);
        }
        info.insert(key.to_string(), items.join(", "));
    }
    reference.info.extend(info);
    eprintln!(
        "{} | scene {} (loaded in {:.2} s) | graph {} layout {layout} | {}x{} | {} spp so far",
        gpu.describe(),
        c.scene(),
        scene.load_seconds,
        graph.name,
        size.0,
        size.1,
        reference.samples_per_pixel()
    );
    let first_frame = first_frame(args.first_frame, &reference)?;
    let mut session = Session::with_layout(&gpu, &graph, &layout, decl, &scene, opts)?;
    session.first_frame = first_frame;
    let bar = match (args.time, args.frames) {
        (Some(t), _) => ProgressBar::new(t.as_millis() as u64),
        (None, frames) => ProgressBar::new(frames.unwrap_or(0) as u64),
    };
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
    let spp_before = reference.samples_per_pixel();
    let start = Instant::now();
    let (mut absorbed_at, mut saved_at) = (Instant::now(), Instant::now());
    let mut seconds_saved = 0.0;
    loop {
        let (step, max) = match (args.time, args.frames) {
            (Some(t), _) => (t.saturating_sub(start.elapsed()), u32::MAX),
            (None, frames) => (Duration::MAX, frames.unwrap_or(0).saturating_sub(session.frames)),
        };
        if step.is_zero() || max == 0 {
            break;
        }
        session.render_for(step.min(Duration::from_millis(100)), max)?;
        if absorbed_at.elapsed() >= ABSORB_EVERY {
            reference.absorb(&session.take_accumulation()?)?;
            absorbed_at = Instant::now();
        }
        if saved_at.elapsed() >= args.checkpoint {
            reference.absorb(&session.take_accumulation()?)?;
            let now = start.elapsed().as_secs_f64();
            reference.seconds += now - seconds_saved;
            seconds_saved = now;
            reference.write(&out, "reference")?;
            saved_at = Instant::now();
        }
        let secs = start.elapsed().as_secs_f64();
        let samples = session.samples_per_pixel() as f64 * (size.0 as f64 * size.1 as f64);
        bar.set_message(format!(
            "{} spp | {} samples/s",
            spp_before + session.samples_per_pixel(),
            si(samples / secs)
        ));
        bar.set_position(match args.time {
            Some(_) => start.elapsed().as_millis() as u64,
            None => session.frames as u64,
        });
    }
    bar.finish();
    reference.absorb(&session.take_accumulation()?)?;
    reference.seconds += start.elapsed().as_secs_f64() - seconds_saved;
    reference.write(&out, "reference")?;
    let png = out.with_extension("png");
    lightgraph::output::write_png(&png, &reference.image(), args.exposure)?;
    println!(
        "wrote {} and {}: {} spp in {:.1} s in all; noise (RMSE of the reference itself) {:.3e}",
        out.display(),
        png.display(),
        reference.samples_per_pixel(),
        reference.seconds,
        reference.noise_floor_mse().sqrt()
    );
    Ok(())
}
