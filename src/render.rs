//! A rendering session: a scene, a graph in one layout, specialised and instantiated on a
//! GPU, run frame after frame into a progressive accumulation.

use anyhow::{Context, Result, anyhow, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::runtime::{IN_FLIGHT, MAX_BATCH};
use lightgraph_engine::{ConstValue, FrameStats, Gpu, Graph, Instance, Plan, Program, Specialization};
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::model::{MisHeuristic, RussianRoulette, Scene};
use lightgraph_scenes::{CompiledScene, parse_scene};
use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant};

/// GPU time of one batch of frames in [`Session::render_for`]: short enough for a live
/// progress line and preview, long enough that recording and reading back stay small.
pub const BATCH_TIME: Duration = Duration::from_millis(100);

/// A scene loaded, validated and prepared for the GPU.
pub struct LoadedScene {
    /// The name it was asked for by.
    pub name: String,
    /// The scene as written.
    pub scene: Scene,
    /// Flattened primitives, lights and BVH.
    pub compiled: CompiledScene,
    /// Seconds spent loading, BVH included.
    pub load_seconds: f64,
}

/// Loads a built-in scene by name, or a scene file by path, with a BVH2.
pub fn load_scene(name: &str) -> Result<LoadedScene> {
    load_scene_with(name, BvhKind::Bvh2)
}

/// Loads a built-in scene by name, a scene file by path, a bare glTF file (`.gltf`, `.glb`;
/// see [`LoadedScene::from_gltf`]) or a Mitsuba scene file (`.xml`,
/// [`LoadedScene::from_mitsuba`]), with a BVH of `kind`; the glTF assets of scene files come
/// from [`crate::assets::asset_root`].
pub fn load_scene_with(name: &str, kind: BvhKind) -> Result<LoadedScene> {
    let lower = name.to_ascii_lowercase();
    let bare_gltf = (lower.ends_with(".gltf") || lower.ends_with(".glb")) && std::path::Path::new(name).is_file();
    let mitsuba = lower.ends_with(".xml") && std::path::Path::new(name).is_file();
    let (file, mut scene) = if bare_gltf {
        (
            name.to_string(),
            LoadedScene::from_gltf(std::path::Path::new(name), kind)?,
        )
    } else if mitsuba {
        (
            name.to_string(),
            LoadedScene::from_mitsuba(std::path::Path::new(name), kind)?,
        )
    } else {
        let (file, text) = crate::assets::scene_text(name).map_err(|e| anyhow!(e))?;
        let scene = LoadedScene::parse(&file, &text, kind, crate::assets::asset_root().as_deref())?;
        (file, scene)
    };
    scene.name = name.to_string();
    if scene.compiled.clipped_primitives > 0 {
        eprintln!(
            "warning: {file}: {} primitives reach beyond ±{:e}, where the BVH clips them: rays do not find those parts",
            scene.compiled.clipped_primitives,
            lightgraph_scenes::TRACED_EXTENT
        );
    }
    Ok(scene)
}

impl LoadedScene {
    /// Parses, validates and compiles the RON scene `text` (`file` names it in errors) with
    /// a BVH of `kind`, importing its glTF asset from below `assets`.
    pub fn parse(file: &str, text: &str, kind: BvhKind, assets: Option<&std::path::Path>) -> Result<LoadedScene> {
        let start = Instant::now();
        let mut scene = parse_scene(file, text)?;
        lightgraph_scenes::resolve_gltf(&mut scene, file, assets)?;
        Self::compile(file.to_string(), scene, kind, start)
    }

    /// Loads the bare glTF file at `path` with a BVH of `kind`: its first camera, else one
    /// framing its bounds, and a constant background when it has no light; says on stderr
    /// which of these defaults it took.
    pub fn from_gltf(path: &std::path::Path, kind: BvhKind) -> Result<LoadedScene> {
        let start = Instant::now();
        let (scene, notes) = lightgraph_scenes::scene_from_gltf(path)?;
        for note in notes {
            eprintln!("note: {}: {note}", path.display());
        }
        Self::compile(path.display().to_string(), scene, kind, start)
    }

    /// Loads the Mitsuba scene file at `path` (lightgraph_scenes::mitsuba) with a BVH of
    /// `kind`; its warnings go to stderr.
    pub fn from_mitsuba(path: &std::path::Path, kind: BvhKind) -> Result<LoadedScene> {
        let start = Instant::now();
        let imported = lightgraph_scenes::mitsuba::load(path)?;
        for warning in &imported.warnings {
            eprintln!("warning: {warning}");
        }
        Self::compile(path.display().to_string(), imported.scene, kind, start)
    }

    /// Compiles `scene` (named `file` in errors) with a BVH of `kind`; its load time counts
    /// from `start`.
    fn compile(file: String, scene: Scene, kind: BvhKind, start: Instant) -> Result<LoadedScene> {
        let compiled = CompiledScene::with_bvh(&scene, kind).map_err(|e| anyhow!("{file}: {e}"))?;
        Ok(LoadedScene {
            name: file,
            scene,
            compiled,
            load_seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// Loads a graph by built-in name or `.ron` path.
pub fn load_graph(name: &str) -> Result<Graph> {
    let (vfs, path) = crate::assets::graph_source(name).map_err(|e| anyhow!(e))?;
    let graph = Graph::load(&vfs, &path)?;
    check_constant_names(&graph)?;
    Ok(graph)
}

/// Every true `Bool` constant of a graph is a preprocessor flag too (docs/graphs.md): one named
/// like a flag the host sets (a scene feature, the BVH's, the device's) would switch that code
/// on or off behind the host's back, so it is an error at its declaration.
fn check_constant_names(graph: &Graph) -> Result<()> {
    let mut host = lightgraph_scenes::features::all();
    host.extend(lightgraph_scenes::bvh::BvhKind::Cwbvh.flag().map(String::from));
    host.insert(FLOAT32_ATOMIC_FLAG.to_string());
    match graph.declared.constants.keys().find(|k| host.contains(*k)) {
        Some(name) => Err(graph
            .error_at_decl(
                name,
                format!("constant '{name}' has the name of a flag the host sets for the kernels (a scene feature, the BVH's or the device's): rename it"),
            )
            .into()),
        None => Ok(()),
    }
}

/// Image size, sampling and seed of a session.
#[derive(Debug, Clone)]
pub struct SessionOptions {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples (camera paths) per pixel in each frame.
    pub samples_per_frame: u32,
    /// Seed of the random streams.
    pub seed: u32,
    /// Constant overrides (`--set NAME=VALUE`, `--max-path-length`).
    pub constants: BTreeMap<String, ConstValue>,
    /// Layout option overrides.
    pub layout: LayoutOverrides,
}

/// Options that override a layout's own (`--threads`, `--workgroup`, `--state`,
/// `--loop-guards`).
#[derive(Debug, Clone, Default)]
pub struct LayoutOverrides {
    /// Thread pool size of regeneration and compaction layouts.
    pub threads: Option<u64>,
    /// Threads per workgroup.
    pub workgroup_size: Option<u32>,
    /// Item state layout between split kernels.
    pub state: Option<lightgraph_engine::ir::StateStorage>,
    /// Compile the code of every scene feature into the kernels, not only the scene's (to
    /// measure what scene-specialised kernels buy).
    pub all_features: bool,
    /// Give every transient buffer memory of its own (no sharing between buffers whose
    /// lifetimes do not overlap).
    pub separate_memory: bool,
    /// Compile without subgroup operations even where the adapter has them (per-item
    /// appends, workgroup-memory scans).
    pub no_subgroups: bool,
    /// Whether the pass kernels keep wgpu's loop guards (the layout's `loop_guards`).
    pub loop_guards: Option<bool>,
}

impl LayoutOverrides {
    /// The compilation target of `gpu` with these overrides.
    pub fn target(&self, gpu: &Gpu) -> lightgraph_engine::Target {
        let target = lightgraph_engine::Target {
            alias_transients: !self.separate_memory,
            ..gpu.target()
        };
        match self.no_subgroups {
            true => target.without_subgroups(),
            false => target,
        }
    }
}

impl LayoutOverrides {
    /// `decl` with these overrides applied.
    pub fn apply(&self, mut decl: LayoutDecl) -> LayoutDecl {
        if self.threads.is_some() {
            decl.threads = self.threads;
        }
        if let Some(w) = self.workgroup_size {
            decl.workgroup_size = w;
        }
        if let Some(s) = self.state {
            decl.state = s;
        }
        if let Some(b) = self.loop_guards {
            decl.loop_guards = b;
        }
        decl
    }
}

/// The constants a scene's integrator settings imply.
pub fn scene_constants(scene: &Scene) -> BTreeMap<String, ConstValue> {
    let i = &scene.integrator;
    let mut c = BTreeMap::new();
    c.insert("MAX_PATH_LENGTH".to_string(), ConstValue::U32(i.max_path_length));
    let (albedo, start, max) = match i.russian_roulette {
        RussianRoulette::Albedo => (true, 1, 1.0),
        RussianRoulette::Throughput { start, max } => (false, start, max),
    };
    c.insert("RR_ALBEDO".to_string(), ConstValue::Bool(albedo));
    c.insert("RR_START".to_string(), ConstValue::U32(start));
    c.insert("RR_MAX".to_string(), ConstValue::F32(max));
    c.insert("MIS_POWER".to_string(), ConstValue::Bool(i.mis == MisHeuristic::Power));
    c
}

/// The flag of kernels on a device with float atomics.
const FLOAT32_ATOMIC_FLAG: &str = "FLOAT32_ATOMIC";

/// Preprocessor flags for the device's optional features.
pub fn device_flags(gpu: &Gpu) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    if gpu.features.contains(wgpu::Features::SHADER_FLOAT32_ATOMIC) {
        flags.insert(FLOAT32_ATOMIC_FLAG.to_string());
    }
    flags
}

/// The preprocessor flags of kernels for `scene`: the device's, the BVH's, and the scene's
/// features (every feature with `all_features`).
pub fn kernel_flags(device: BTreeSet<String>, scene: &LoadedScene, all_features: bool) -> BTreeSet<String> {
    let mut flags = device;
    flags.extend(scene.compiled.bvh_kind.flag().map(String::from));
    flags.extend(if all_features {
        lightgraph_scenes::features::all()
    } else {
        lightgraph_scenes::features::used(&scene.compiled)
    });
    flags
}

/// The specialisation of a graph for a scene and options: host constants (image size,
/// paths per frame), the scene's integrator constants, then the overrides. Only constants
/// the graph declares are taken from the scene.
pub fn specialization(graph: &Graph, scene: &Scene, opts: &SessionOptions, flags: BTreeSet<String>) -> Specialization {
    let pixels = opts.width * opts.height;
    let mut constants = BTreeMap::new();
    constants.insert("WIDTH".to_string(), ConstValue::U32(opts.width));
    constants.insert("HEIGHT".to_string(), ConstValue::U32(opts.height));
    constants.insert("PIXELS".to_string(), ConstValue::U32(pixels));
    constants.insert("SAMPLES_PER_PIXEL".to_string(), ConstValue::U32(opts.samples_per_frame));
    constants.insert("PATHS".to_string(), ConstValue::U32(pixels * opts.samples_per_frame));
    for (k, v) in scene_constants(scene) {
        if graph.constants.contains_key(&k) {
            constants.insert(k, v);
        }
    }
    constants.extend(opts.constants.clone());
    Specialization { constants, flags }
}

/// A per-pixel image: the mean of the frames' estimates and their variance.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Frames accumulated.
    pub frames: u32,
    /// Mean radiance per pixel (row-major, top row first).
    pub mean: Vec<[f32; 3]>,
    /// Sample variance of the per-frame estimates (the squared standard error of the mean is
    /// this over `frames`).
    pub variance: Vec<[f32; 3]>,
}

/// The GPU's progressive sums: per pixel, the sum of the frames' estimates and of their
/// squares.
#[derive(Debug, Clone)]
pub struct Accumulation {
    /// The frame indices summed: sorted, disjoint half-open ranges.
    pub ranges: Vec<(u64, u64)>,
    /// Frames summed.
    pub frames: u32,
    /// Sum of the per-frame estimates (RGB, fourth word unused).
    pub sum: Vec<[f32; 4]>,
    /// Sum of their squares.
    pub sum_sq: Vec<[f32; 4]>,
}

/// A scene rendered by a graph in one layout.
pub struct Session<'g> {
    instance: Instance<'g>,
    /// Options of the session.
    pub options: SessionOptions,
    /// Frames rendered (submitted to the GPU; [`Session::settled`] of them read back).
    pub frames: u32,
    /// Frames whose statistics are in `counters` and `kernel_seconds`: the frames
    /// rendered less those of the batches still in flight.
    pub settled: u32,
    /// Frames of each batch submitted and not yet read back, oldest first.
    in_flight: std::collections::VecDeque<u32>,
    /// Frame index of the session's first frame: a resumed render continues the random
    /// streams where the earlier one stopped instead of repeating them.
    pub first_frame: u32,
    /// The frame indices rendered since [`Session::take_accumulation`] last emptied the GPU
    /// accumulation (what it holds), adjacent ones joined.
    pending: Vec<(u64, u64)>,
    /// Counter totals of the settled frames.
    pub counters: BTreeMap<String, u64>,
    /// GPU time per kernel, summed over the settled frames.
    pub kernel_seconds: BTreeMap<String, f64>,
    /// Loops stopped by the iteration cap (must stay 0).
    pub loops_capped: u64,
}

impl<'g> Session<'g> {
    /// Plans, compiles and instantiates `graph` in its layout called `layout` for `scene`.
    pub fn new(
        gpu: &'g Gpu,
        graph: &Graph,
        layout: &str,
        scene: &LoadedScene,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        // Resolving by name first gives the error that lists the graph's layouts.
        let decl = Plan::new(graph, layout)?.layout;
        Self::with_layout(gpu, graph, layout, decl, scene, options)
    }

    /// Plans, compiles and instantiates `graph` in the layout `decl` (named `layout`). The
    /// graph's measured constants not given in the options are measured first
    /// ([`measure_constants`]).
    pub fn with_layout(
        gpu: &'g Gpu,
        graph: &Graph,
        layout: &str,
        decl: LayoutDecl,
        scene: &LoadedScene,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        let Prepared {
            plan,
            mut spec,
            externals,
        } = prepare(gpu, graph, layout, decl, scene, &options)?;
        let measured = measure_prepared(gpu, graph, layout, (&plan, &spec, &externals), &options)?;
        spec.constants.extend(measured);
        let program = Program::compile(&plan, &spec, &options.layout.target(gpu))?;
        let instance = Instance::new(gpu, program, &externals)
            .with_context(|| format!("instantiating graph '{}' in layout '{layout}'", graph.name))?;
        Ok(Session {
            instance,
            options,
            frames: 0,
            settled: 0,
            in_flight: Default::default(),
            first_frame: 0,
            pending: Vec::new(),
            counters: BTreeMap::new(),
            kernel_seconds: BTreeMap::new(),
            loops_capped: 0,
        })
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        self.instance.program()
    }

    /// Renders one more frame (or [`Session::frames_at_once`] frames where the graph runs
    /// several as one).
    pub fn render_frame(&mut self) -> Result<FrameStats> {
        self.render_frames(self.frames_at_once())
    }

    /// Frames the GPU renders as one (the graph's `FRAMES_AT_ONCE`, passes/film.ron; 1 for a
    /// graph without it): batches and frame indices then come in multiples of it.
    pub fn frames_at_once(&self) -> u32 {
        match self.instance.program().constants().get("FRAMES_AT_ONCE") {
            Some(ConstValue::U32(n)) => (*n).max(1),
            _ => 1,
        }
    }

    /// Checks that frames `first .. first + count` are whole groups of the frames the GPU
    /// renders as one ([`Session::frames_at_once`]).
    pub fn check_frames(&self, first: u32, count: u32) -> Result<()> {
        let at_once = self.frames_at_once();
        if !count.is_multiple_of(at_once) || !first.is_multiple_of(at_once) {
            bail!(
                "frames {first} to {} do not start and end at multiples of FRAMES_AT_ONCE = {at_once} \
                 (the frames the GPU renders as one): render and resume a multiple of {at_once} frames",
                first as u64 + count as u64
            );
        }
        Ok(())
    }

    /// Goes on at frame index `first` instead of the next one: frames claimed out of order
    /// (by several GPUs or ranks sharing a run). The accumulation records which frames it holds.
    pub fn jump_to(&mut self, first: u32) -> Result<()> {
        self.first_frame = first
            .checked_sub(self.frames)
            .ok_or_else(|| anyhow!("frame {first} is before the {} frames rendered", self.frames))?;
        Ok(())
    }

    /// Renders `count` more frames (at most [`MAX_BATCH`] times [`Session::frames_at_once`],
    /// a multiple of it) recorded together, with one
    /// read-back of statistics, and waits for them (and any batch still in flight); returns
    /// the statistics of the frames it waited for.
    pub fn render_frames(&mut self, count: u32) -> Result<FrameStats> {
        self.submit(count)?;
        self.settle()
    }

    /// Renders toward a budget, keeping the GPU busy: submits a batch of about
    /// [`BATCH_TIME`] of frames (at most `max`, and no more than fills the `left` time of a
    /// timed run, counting the batch still running), then reads back the batch before it,
    /// so that the host records and reads back while the GPU runs. Returns the statistics of
    /// the batches read back (empty when none finished; [`Session::settle`] reads the rest).
    /// Until a frame's GPU time is known (always, on an adapter without timestamp queries) it
    /// renders one frame and waits for it. Frames come in multiples of
    /// [`Session::frames_at_once`].
    pub fn render_for(&mut self, left: Option<Duration>, max: u32) -> Result<FrameStats> {
        let at_once = self.frames_at_once();
        let per_frame = self.kernel_seconds.values().sum::<f64>() / self.settled.max(1) as f64;
        if self.settled == 0 || per_frame <= 0.0 {
            return self.render_frames(max.min(at_once));
        }
        let queued = self.in_flight.iter().sum::<u32>() as f64 * per_frame;
        let room = left.map_or(f64::INFINITY, |t| t.as_secs_f64() - queued);
        let most = (MAX_BATCH * at_once) as f64;
        let wanted = (room.min(BATCH_TIME.as_secs_f64()) / per_frame).clamp(0.0, most) as u32;
        let count = match wanted.min(max) / at_once * at_once {
            // A timed run with less than a frame left still renders one, unless the batch in
            // flight ends it.
            0 if self.in_flight.is_empty() => max.min(at_once),
            n => n,
        };
        match count {
            0 => self.settle(),
            _ => self.render_frames_behind(count),
        }
    }

    /// Submits `count` more frames (as [`Session::render_frames`]) and reads back the batches
    /// before them, leaving this one running, so that the host records the next batch while
    /// the GPU renders; returns the statistics of the batches read back
    /// ([`Session::settle`] reads the rest).
    pub fn render_frames_behind(&mut self, count: u32) -> Result<FrameStats> {
        self.submit(count)?;
        let mut stats = FrameStats::default();
        while self.in_flight.len() > 1 {
            stats.add(&self.collect()?);
        }
        Ok(stats)
    }

    /// Reads back every batch still in flight (waiting for them); returns their statistics.
    /// Counters and GPU times cover every frame rendered after it.
    pub fn settle(&mut self) -> Result<FrameStats> {
        let mut stats = FrameStats::default();
        while !self.in_flight.is_empty() {
            stats.add(&self.collect()?);
        }
        Ok(stats)
    }

    /// Submits `count` frames (at most [`MAX_BATCH`] of the GPU's, each
    /// [`Session::frames_at_once`] frames) as one batch; at most one other batch stays in
    /// flight (an older one is read back first).
    fn submit(&mut self, count: u32) -> Result<()> {
        if self.first_frame as u64 + self.frames as u64 + count as u64 > u32::MAX as u64 {
            bail!("the frame index would pass 2^32; continue with another seed");
        }
        let first = self.first_frame + self.frames;
        self.check_frames(first, count)?;
        let at_once = self.frames_at_once();
        while self.in_flight.len() >= IN_FLIGHT {
            self.collect()?;
        }
        self.instance
            .submit_frames(first / at_once, count / at_once, self.options.seed)?;
        self.in_flight.push_back(count);
        self.frames += count;
        let range = (first as u64, first as u64 + count as u64);
        match self.pending.last_mut() {
            Some(last) if last.1 == range.0 => last.1 = range.1,
            _ => self.pending.push(range),
        }
        Ok(())
    }

    /// Waits for the oldest batch in flight and adds its statistics to the session's.
    fn collect(&mut self) -> Result<FrameStats> {
        let stats = self
            .instance
            .collect_frames()?
            .ok_or_else(|| anyhow!("no batch of frames in flight"))?;
        let count = self.in_flight.pop_front().expect("a batch in flight");
        self.settled += count;
        stats.add_to(&mut self.counters, &mut self.kernel_seconds);
        self.loops_capped += stats.loops_capped as u64;
        Ok(stats)
    }

    /// GPU memory of the session: the buffers the layout allocates (transient ones sharing
    /// memory) and the scene data.
    pub fn memory_bytes(&self) -> u64 {
        let program = self.instance.program();
        let external: u64 = program
            .resolved
            .sizes
            .iter()
            .filter_map(|(name, size)| {
                self.instance
                    .external_count(name)
                    .map(|n| n * size.element_bytes as u64)
            })
            .sum();
        program.peak_bytes() + external
    }

    /// Rays traced so far (primary, extension and shadow counters of the graph).
    pub fn rays(&self) -> u64 {
        self.counters
            .iter()
            .filter(|(k, _)| k.starts_with("rays_"))
            .map(|(_, v)| v)
            .sum()
    }

    /// Samples per pixel accumulated so far.
    pub fn samples_per_pixel(&self) -> u64 {
        self.frames as u64 * self.options.samples_per_frame as u64
    }

    /// Reads the GPU accumulation: the number of frames in it, the per-pixel sums of the
    /// frames' estimates and the sums of their squares (RGB and an unused fourth word).
    pub fn accumulation(&self) -> Result<Accumulation> {
        Ok(Accumulation {
            ranges: self.pending.clone(),
            frames: self.pending.iter().map(|r| (r.1 - r.0) as u32).sum(),
            sum: bytemuck::pod_collect_to_vec(&self.instance.read("accum")?),
            sum_sq: bytemuck::pod_collect_to_vec(&self.instance.read("accum_sq")?),
        })
    }

    /// Reads the GPU accumulation and empties it, so a host accumulator (in f64) can take
    /// the sums over and the f32 sums on the GPU stay short.
    pub fn take_accumulation(&mut self) -> Result<Accumulation> {
        self.settle()?;
        let taken = self.accumulation()?;
        for name in ["accum", "accum_comp", "accum_sq"] {
            self.instance.clear(name)?;
        }
        self.pending.clear();
        Ok(taken)
    }

    /// Renders a frame and throws it away, leaving the session as new (frame 0 next, nothing
    /// accumulated or counted) with every pipeline used once: a driver that compiles a
    /// pipeline at its first dispatch (lavapipe) does it here, before a timed run's clock.
    pub fn warm_up(&mut self) -> Result<()> {
        self.render_frame()?;
        self.take_accumulation()?;
        self.frames = 0;
        self.settled = 0;
        self.counters.clear();
        self.kernel_seconds.clear();
        self.loops_capped = 0;
        Ok(())
    }

    /// The accumulated image (reads the GPU accumulation).
    pub fn image(&self) -> Result<Image> {
        let (w, h) = (self.options.width, self.options.height);
        let Accumulation {
            frames,
            sum,
            sum_sq: sq,
            ..
        } = self.accumulation()?;
        let n = frames.max(1) as f64;
        let mut mean = Vec::with_capacity(sum.len());
        let mut variance = Vec::with_capacity(sum.len());
        for (s, q) in sum.iter().zip(&sq) {
            let m = [0, 1, 2].map(|c| s[c] as f64 / n);
            mean.push(m.map(|v| v as f32));
            variance.push([0, 1, 2].map(|c| {
                if n > 1.0 {
                    (((q[c] as f64) / n - m[c] * m[c]) * n / (n - 1.0)).max(0.0) as f32
                } else {
                    0.0
                }
            }));
        }
        Ok(Image {
            width: w,
            height: h,
            frames,
            mean,
            variance,
        })
    }
}

/// What a session is compiled from: the plan, the specialization and the scene's resources
/// the graph declares.
struct Prepared {
    plan: Plan,
    spec: Specialization,
    externals: BTreeMap<String, Vec<u8>>,
}

/// Checks the options and plans and specializes `graph` in the layout `decl` for `scene`.
fn prepare(
    gpu: &Gpu,
    graph: &Graph,
    layout: &str,
    decl: LayoutDecl,
    scene: &LoadedScene,
    options: &SessionOptions,
) -> Result<Prepared> {
    if options.width == 0 || options.height == 0 || options.samples_per_frame == 0 {
        bail!("resolution and samples per frame must be at least 1");
    }
    let paths = options.width as u64 * options.height as u64 * options.samples_per_frame as u64;
    if paths > u32::MAX as u64 {
        bail!("{paths} paths per frame is more than 2^32; use fewer samples per frame");
    }
    let plan = Plan::with_decl(graph, layout, options.layout.apply(decl))?;
    let flags = kernel_flags(device_flags(gpu), scene, options.layout.all_features);
    let spec = specialization(graph, &scene.scene, options, flags);
    let camera = CompiledScene::camera(&scene.scene, options.width, options.height);
    // The scene offers every scene resource; a graph takes those it declares.
    let mut externals = scene.compiled.resources(&camera);
    externals.retain(|name, _| {
        graph
            .resources
            .get(name)
            .is_some_and(|r| r.scope == lightgraph_engine::ir::Scope::External)
    });
    check_scene_fits(gpu, scene, &externals)?;
    Ok(Prepared { plan, spec, externals })
}

/// An error naming the scene's size where one of its buffers is larger than `gpu` binds or
/// holds in one buffer (its triangles, BVH nodes, textures...), before any is made.
fn check_scene_fits(gpu: &Gpu, scene: &LoadedScene, externals: &BTreeMap<String, Vec<u8>>) -> Result<()> {
    let limit = gpu
        .limits
        .max_storage_buffer_binding_size
        .min(gpu.limits.max_buffer_size);
    let mib = |bytes: u64| bytes as f64 / 1048576.0;
    if let Some((name, size)) = largest_over(externals, limit) {
        bail!(
            "the scene is too large for this GPU: its '{name}' buffer takes {:.1} MiB ({} primitives, a BVH of {:.1} MiB), more than the {:.1} MiB the adapter binds in one storage buffer (max_storage_buffer_binding_size {}, max_buffer_size {})",
            mib(size),
            scene.compiled.primitives.len(),
            mib(scene.compiled.bvh.len() as u64),
            mib(limit),
            gpu.limits.max_storage_buffer_binding_size,
            gpu.limits.max_buffer_size,
        );
    }
    Ok(())
}

/// The largest of `buffers` (name and bytes) over `limit` bytes, if any.
fn largest_over(buffers: &BTreeMap<String, Vec<u8>>, limit: u64) -> Option<(&str, u64)> {
    buffers
        .iter()
        .map(|(name, bytes)| (name.as_str(), bytes.len() as u64))
        .filter(|&(_, size)| size > limit)
        .max_by_key(|&(_, size)| size)
}

/// Measures the graph's measured constants that `options` does not give (LVC-BPT's average
/// light sub-path length): one frame each with its measuring constants set. Runs that are
/// merged (shards, GPUs, ranks, a resumed reference) must share one measurement, or they
/// render different estimators: measure once and put the values into every run's constants.
pub fn measure_constants(
    gpu: &Gpu,
    graph: &Graph,
    layout: &str,
    decl: LayoutDecl,
    scene: &LoadedScene,
    options: &SessionOptions,
) -> Result<BTreeMap<String, ConstValue>> {
    if graph.measured.keys().all(|name| options.constants.contains_key(name)) {
        return Ok(BTreeMap::new());
    }
    let Prepared { plan, spec, externals } = prepare(gpu, graph, layout, decl, scene, options)?;
    measure_prepared(gpu, graph, layout, (&plan, &spec, &externals), options)
}

/// [`measure_constants`] on a prepared plan and specialization.
fn measure_prepared(
    gpu: &Gpu,
    graph: &Graph,
    layout: &str,
    (plan, spec, externals): (&Plan, &Specialization, &BTreeMap<String, Vec<u8>>),
    options: &SessionOptions,
) -> Result<BTreeMap<String, ConstValue>> {
    let mut measured = BTreeMap::new();
    for (name, m) in &graph.measured {
        if options.constants.contains_key(name) {
            continue;
        }
        let mut measuring = spec.clone();
        measuring.constants.extend(measured.clone());
        measuring.constants.extend(m.set.clone());
        let program = Program::compile(plan, &measuring, &options.layout.target(gpu))?;
        let mut instance = Instance::new(gpu, program, externals)
            .with_context(|| format!("measuring '{name}' of graph '{}' in layout '{layout}'", graph.name))?;
        let stats = instance.run_frames(0, 1, options.seed)?;
        let (a, b) = (stats.counters[&m.ratio.0], stats.counters[&m.ratio.1]);
        let value = m.value_from(a, b, &measuring.constants).map_err(|why| {
            let hint = if m.value.is_none() {
                " (no light in the scene?)"
            } else {
                ""
            };
            anyhow!("measuring '{name}' of graph '{}': {why}{hint}", graph.name)
        })?;
        measured.insert(name.clone(), ConstValue::F32(value as f32));
    }
    Ok(measured)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_buffer_over_the_limit_is_named() {
        let buffers: BTreeMap<String, Vec<u8>> = [("bvh", 300), ("primitives", 500), ("lights", 10)]
            .into_iter()
            .map(|(n, size)| (n.to_string(), vec![0u8; size]))
            .collect();
        assert_eq!(largest_over(&buffers, 200), Some(("primitives", 500)));
        assert_eq!(largest_over(&buffers, 500), None);
    }
}
