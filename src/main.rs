//! The `lightgraph` command line: render, explain, list.

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::render::{LayoutOverrides, LoadedScene, Session, SessionOptions, load_graph, load_scene_with};
use lightgraph::{assets, output};
use lightgraph_engine::ir::StateStorage;
use lightgraph_engine::{ConstValue, Gpu, Plan, Program};
use lightgraph_scenes::bvh::BvhKind;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "lightgraph",
    version,
    about = "GPU progressive light transport: algorithms as frame graphs of compute passes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene progressively and write an EXR and a PNG preview.
    Render(RenderArgs),
    /// Print the kernels, schedule and resources of a graph's layouts.
    Explain(ExplainArgs),
    /// Measure layouts over a sweep of paths per frame: Markdown table, CSV and PNG plot.
    Bench(BenchArgs),
    /// List built-in graphs with their layouts, built-in scenes and GPU adapters.
    List,
}

#[derive(Args)]
struct BenchArgs {
    #[command(flatten)]
    common: Common,
    /// Layouts to measure, comma-separated; `all` for the graph's named layouts, `auto` for
    /// every legal layout the engine finds.
    #[arg(long, default_value = "all")]
    layouts: String,
    /// Frame sizes as WxHxSPP, comma-separated (default: 3.3e5 to 1e8 paths per frame).
    #[arg(long)]
    points: Option<String>,
    /// Time each layout renders at each frame size (after a warm-up frame).
    #[arg(long, value_parser = humantime::parse_duration, default_value = "2s")]
    time: Duration,
    /// Output folder for bench.md, bench.csv and rays_per_second.png.
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
}

#[derive(Args, Clone)]
struct Common {
    /// Scene: a built-in name (see `lightgraph list`) or a .ron scene file.
    #[arg(long, default_value = "cornell-mitsuba")]
    scene: String,
    /// Graph: a built-in name or a .ron graph file.
    #[arg(long, default_value = "pt")]
    graph: String,
    /// Image size WxH (default: the scene's).
    #[arg(long, value_parser = parse_resolution)]
    res: Option<(u32, u32)>,
    /// Samples per pixel in each frame.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Maximum path length in segments (default: the scene's).
    #[arg(long)]
    max_path_length: Option<u32>,
    /// Override a graph constant, NAME=VALUE (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Folder scene files find their glTF assets in (also LIGHTGRAPH_ASSETS; default:
    /// ../shared/scenes when it exists).
    #[arg(long, env = "LIGHTGRAPH_ASSETS")]
    assets: Option<PathBuf>,
    /// GPU adapter whose name contains this text (also LIGHTGRAPH_ADAPTER).
    #[arg(long, env = "LIGHTGRAPH_ADAPTER")]
    adapter: Option<String>,
    /// Thread pool of regeneration and compaction layouts (overrides the layout's).
    #[arg(long)]
    threads: Option<u64>,
    /// Threads per workgroup (overrides the layout's).
    #[arg(long)]
    workgroup: Option<u32>,
    /// Item state between split kernels: soa or aos (overrides the layout's).
    #[arg(long, value_parser = parse_state)]
    state: Option<StateStorage>,
    /// Acceleration structure: bvh2 (binary, both children's boxes per node) or cwbvh
    /// (compressed 8-wide, Ylitie et al. 2017).
    #[arg(long, value_parser = parse_bvh, default_value = "cwbvh")]
    bvh: BvhKind,
}

fn parse_bvh(s: &str) -> Result<BvhKind, String> {
    match s.to_lowercase().as_str() {
        "bvh2" => Ok(BvhKind::Bvh2),
        "cwbvh" => Ok(BvhKind::Cwbvh),
        _ => Err(format!("'{s}' is not bvh2 or cwbvh")),
    }
}

fn parse_state(s: &str) -> Result<StateStorage, String> {
    match s.to_lowercase().as_str() {
        "soa" => Ok(StateStorage::SoA),
        "aos" => Ok(StateStorage::AoS),
        _ => Err(format!("'{s}' is not soa or aos")),
    }
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    common: Common,
    /// Kernel layout (default: the graph's); `auto` measures every legal layout first and
    /// renders with the fastest.
    #[arg(long)]
    layout: Option<String>,
    /// Time each layout gets when --layout auto measures it.
    #[arg(long, value_parser = humantime::parse_duration, default_value = "500ms")]
    tune_time: Duration,
    /// Render for this long (e.g. 10s, 2m); overrides --frames.
    #[arg(long, value_parser = humantime::parse_duration)]
    time: Option<Duration>,
    /// Frames to render.
    #[arg(long, default_value_t = 64)]
    frames: u32,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Output EXR; a PNG preview is written beside it.
    #[arg(long, default_value = "out/render.exr")]
    out: PathBuf,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
}

#[derive(Args)]
struct ExplainArgs {
    #[command(flatten)]
    common: Common,
    /// Layout to explain (default: all of the graph's layouts).
    #[arg(long)]
    layout: Option<String>,
    /// Also write the graph as Graphviz DOT to this file.
    #[arg(long)]
    dot: Option<PathBuf>,
    /// Also write each kernel's generated WGSL into this folder.
    #[arg(long)]
    wgsl: Option<PathBuf>,
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WxH"))?;
    let w: u32 = w.parse().map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height in '{s}'"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}' has a zero side"));
    }
    Ok((w, h))
}

/// Parses `--set` values with the type of the graph's default (u32 when it has none).
fn parse_sets(sets: &[String], defaults: &BTreeMap<String, ConstValue>) -> Result<BTreeMap<String, ConstValue>> {
    let mut out = BTreeMap::new();
    for s in sets {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| anyhow!("--set {s}: expected NAME=VALUE"))?;
        let bad = || anyhow!("--set {s}: '{value}' is not a valid value for {name}");
        let v = match defaults.get(name) {
            Some(ConstValue::F32(_)) => ConstValue::F32(value.parse().map_err(|_| bad())?),
            Some(ConstValue::I32(_)) => ConstValue::I32(value.parse().map_err(|_| bad())?),
            Some(ConstValue::Bool(_)) => ConstValue::Bool(value.parse().map_err(|_| bad())?),
            _ => ConstValue::U32(value.parse().map_err(|_| bad())?),
        };
        out.insert(name.to_string(), v);
    }
    Ok(out)
}

fn options(
    common: &Common,
    scene: &LoadedScene,
    defaults: &BTreeMap<String, ConstValue>,
    seed: u32,
) -> Result<SessionOptions> {
    let (width, height) = common.res.unwrap_or(scene.scene.resolution);
    let mut constants = parse_sets(&common.set, defaults)?;
    if let Some(n) = common.max_path_length {
        if n == 0 {
            bail!("--max-path-length must be at least 1");
        }
        constants.insert("MAX_PATH_LENGTH".into(), ConstValue::U32(n));
    }
    let layout = LayoutOverrides {
        threads: common.threads,
        workgroup_size: common.workgroup,
        state: common.state,
    };
    Ok(SessionOptions {
        width,
        height,
        samples_per_frame: common.spp,
        seed,
        constants,
        layout,
    })
}

fn si(v: f64) -> String {
    match v {
        v if v >= 1e9 => format!("{:.2} G", v / 1e9),
        v if v >= 1e6 => format!("{:.2} M", v / 1e6),
        v if v >= 1e3 => format!("{:.2} k", v / 1e3),
        v => format!("{v:.1} "),
    }
}

fn render(args: RenderArgs) -> Result<()> {
    let c = &args.common;
    let scene = load_scene_with(&c.scene, c.bvh)?;
    let graph = load_graph(&c.graph)?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    let opts = options(c, &scene, &graph.constants, args.seed)?;
    let (layout, decl) = match args.layout.as_deref() {
        Some("auto") => {
            eprintln!(
                "--layout auto: measuring every legal layout of '{}' for {:?} each",
                graph.name, args.tune_time
            );
            let trials = lightgraph::tune::autotune(&gpu, &graph, &scene, &opts, args.tune_time, |t| {
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
            (best.name.clone(), best.decl.clone())
        }
        Some(name) => (name.to_string(), Plan::new(&graph, name)?.layout),
        None => (
            graph.default_layout.clone(),
            graph.layouts[&graph.default_layout].clone(),
        ),
    };
    let (w, h) = (opts.width, opts.height);
    eprintln!(
        "{} | scene {} ({} primitives, {} lights, loaded in {:.2} s) | graph {} layout {} | {w}x{h}",
        gpu.describe(),
        c.scene,
        scene.compiled.primitives.len(),
        scene.compiled.lights.len(),
        scene.load_seconds,
        graph.name,
        layout
    );
    let mut session = Session::with_layout(&gpu, &graph, &layout, decl, &scene, opts)?;
    let bar = match args.time {
        Some(t) => ProgressBar::new(t.as_millis() as u64),
        None => ProgressBar::new(args.frames as u64),
    };
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
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
            Some(t) => session.render_for(t.saturating_sub(elapsed).min(Duration::from_millis(100)), u32::MAX)?,
            None => session.render_for(Duration::from_millis(100), args.frames - session.frames)?,
        };
        let secs = start.elapsed().as_secs_f64();
        let samples = session.samples_per_pixel() as f64 * (w as f64 * h as f64);
        bar.set_message(format!(
            "frame {} | {} samples/s | {}rays/s",
            session.frames,
            si(samples / secs),
            si(session.rays() as f64 / secs)
        ));
        match args.time {
            Some(_) => bar.set_position(start.elapsed().as_millis() as u64),
            None => bar.set_position(session.frames as u64),
        }
    }
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    let rejected = session.counters.get("samples_rejected").copied().unwrap_or(0);
    let image = session.image()?;
    let metadata = [
        ("graph", graph.name.clone()),
        ("layout", layout.clone()),
        ("scene", c.scene.clone()),
        ("samples_per_pixel", session.samples_per_pixel().to_string()),
        ("frames", session.frames.to_string()),
        ("seconds", format!("{seconds:.3}")),
        ("seed", args.seed.to_string()),
        ("adapter", gpu.info.name.clone()),
        ("rays", session.rays().to_string()),
        ("rejected_samples", rejected.to_string()),
    ];
    output::write_exr(&args.out, &image, &metadata)?;
    let png = args.out.with_extension("png");
    output::write_png(&png, &image, args.exposure)?;
    let gpu_time: f64 = session.kernel_seconds.values().sum();
    let frames = session.frames.max(1) as f64;
    let samples = session.samples_per_pixel() as f64 * (w * h) as f64;
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
    println!("wrote {} and {}", args.out.display(), png.display());
    Ok(())
}

fn explain(args: ExplainArgs) -> Result<()> {
    let c = &args.common;
    let graph = load_graph(&c.graph)?;
    let scene = load_scene_with(&c.scene, c.bvh)?;
    let opts = options(c, &scene, &graph.constants, 1)?;
    let layouts: Vec<String> = match &args.layout {
        Some(l) => vec![l.clone()],
        None => graph.layouts.keys().cloned().collect(),
    };
    let flags = Gpu::new(c.adapter.as_deref())
        .ok()
        .map(|g| (lightgraph::render::device_flags(&g), g.target()));
    let (flags, target) = flags.unwrap_or_default();
    let spec = lightgraph::render::specialization(&graph, &scene.scene, &opts, flags);
    let camera = lightgraph_scenes::CompiledScene::camera(&scene.scene, opts.width, opts.height);
    let externals = scene.compiled.resources(&camera);
    println!(
        "layouts of graph '{}': {}\n",
        graph.name,
        graph.layouts.keys().cloned().collect::<Vec<_>>().join(", ")
    );
    for layout in layouts {
        let plan = Plan::new(&graph, &layout)?;
        let program = Program::compile(&plan, &spec, &target)?;
        println!(
            "{}",
            lightgraph_engine::explain::report(&program, &|name| externals.get(name).map(|b| b.len() as u64))
        );
        if let Some(dir) = &args.wgsl {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            for k in &program.kernels {
                let path = dir.join(format!("{}-{}-{}.wgsl", graph.name, layout, k.name));
                std::fs::write(&path, k.source.text()).with_context(|| format!("writing {}", path.display()))?;
            }
        }
    }
    if let Some(dot) = &args.dot {
        std::fs::write(dot, graph.to_dot()).with_context(|| format!("writing {}", dot.display()))?;
        println!("wrote {}", dot.display());
    }
    Ok(())
}

fn bench(args: BenchArgs) -> Result<()> {
    let c = &args.common;
    let scene = load_scene_with(&c.scene, c.bvh)?;
    let graph = load_graph(&c.graph)?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    let points: Vec<(u32, u32, u32)> = match &args.points {
        None => lightgraph::bench::DEFAULT_POINTS.to_vec(),
        Some(list) => list
            .split(',')
            .map(|p| {
                let v: Vec<u32> = p.split(['x', 'X']).filter_map(|n| n.trim().parse().ok()).collect();
                match v.as_slice() {
                    [w, h, s] if *w > 0 && *h > 0 && *s > 0 => Ok((*w, *h, *s)),
                    _ => Err(anyhow!("--points: '{p}' is not WxHxSPP")),
                }
            })
            .collect::<Result<_>>()?,
    };
    let layouts: Vec<(String, lightgraph_engine::ir::LayoutDecl)> = match args.layouts.as_str() {
        "all" => graph.layouts.iter().map(|(n, d)| (n.clone(), d.clone())).collect(),
        "auto" => lightgraph_engine::auto::legal_layouts(&graph, &graph.layouts[&graph.default_layout]),
        list => list
            .split(',')
            .map(|n| Ok((n.to_string(), Plan::new(&graph, n)?.layout)))
            .collect::<Result<_>>()?,
    };
    eprintln!(
        "{} | scene {} | graph {} | {} layouts x {} frame sizes, {:?} each",
        gpu.describe(),
        c.scene,
        graph.name,
        layouts.len(),
        points.len(),
        args.time
    );
    let mut results = Vec::new();
    for (w, h, spp) in points {
        for (name, decl) in &layouts {
            let mut opts = options(c, &scene, &graph.constants, 1)?;
            (opts.width, opts.height, opts.samples_per_frame) = (w, h, spp);
            match lightgraph::bench::measure(&gpu, &graph, name, decl.clone(), &scene, opts, args.time) {
                Ok(m) => {
                    eprintln!(
                        "  {:>8.2} M paths  {:<20} {:>8.1} Mrays/s ({:>8.1} GPU) {:>8.1} Msamples/s {:>7.1} fps {:>8.1} MiB",
                        m.paths_per_frame() as f64 / 1e6,
                        name,
                        m.rays_per_second() / 1e6,
                        m.gpu_rays_per_second() / 1e6,
                        m.samples_per_second() / 1e6,
                        m.frames_per_second(),
                        m.memory_bytes as f64 / 1048576.0
                    );
                    results.push(m);
                }
                Err(e) => eprintln!(
                    "  {:>8.2} M paths  {name}: failed: {e:#}",
                    (w * h) as f64 * spp as f64 / 1e6
                ),
            }
        }
    }
    let title = format!(
        "{} on {}, {} ({})",
        graph.name,
        c.scene,
        gpu.info.name,
        if args.layouts == "auto" {
            "every legal layout"
        } else {
            "named layouts"
        }
    );
    let md = lightgraph::bench::write_reports(&args.out, &title, &results)?;
    println!(
        "{md}\nwrote {}/bench.md, bench.csv and rays_per_second.png",
        args.out.display()
    );
    Ok(())
}

fn list() -> Result<()> {
    println!("graphs:");
    for name in assets::graph_names() {
        match load_graph(&name) {
            Ok(g) => println!(
                "  {name}: {} (layouts: {}; default {})",
                g.description,
                g.layouts.keys().cloned().collect::<Vec<_>>().join(", "),
                g.default_layout
            ),
            Err(e) => println!("  {name}: cannot load: {e}"),
        }
    }
    println!("scenes:");
    for (name, path) in assets::scene_names() {
        println!("  {name} ({path})");
    }
    println!("adapters:");
    let adapters = lightgraph_engine::gpu::adapters();
    if adapters.is_empty() {
        println!("  none: {}", lightgraph_engine::gpu::NO_ADAPTER_HELP);
    }
    for a in adapters {
        println!("  {} ({:?}, {:?}, {})", a.name, a.backend, a.device_type, a.driver);
    }
    Ok(())
}

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread starts; silences the Vulkan loader's warning.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let assets = match &cli.command {
        Command::Render(a) => a.common.assets.clone(),
        Command::Explain(a) => a.common.assets.clone(),
        Command::Bench(a) => a.common.assets.clone(),
        Command::List => None,
    };
    if let Some(dir) = assets {
        // SAFETY: set before any thread starts; scene loading reads it.
        unsafe { std::env::set_var("LIGHTGRAPH_ASSETS", dir) };
    }
    let result = match cli.command {
        Command::Render(a) => render(a),
        Command::Explain(a) => explain(a),
        Command::Bench(a) => bench(a),
        Command::List => list(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
