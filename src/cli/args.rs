//! Options shared by the commands: scene, graph, resolution, constants, layout overrides.

use super::checks::count;
use anyhow::Result;
use clap::Args;
use lightgraph::compare::RunBudget;
pub use lightgraph::compare::estimator_specs;
use lightgraph::compare::render::{Comparison, PER_DECADE};
use lightgraph::film::Film;
use lightgraph::interrupt::Interrupted;
use lightgraph::output::shell_word;
pub use lightgraph::output::si;
pub use lightgraph::run::scene::find_scene;
use lightgraph::run::{
    BvhChoice, DEFAULT_GRAPH, DEFAULT_SCENE, DEFAULT_SEED, LayoutOverrides, LoadedScene, RunOptions, RunSpec,
    SessionOptions,
};
use lightgraph::tev::LiveView;
use lightgraph::tuning::Tuning;
use lightgraph_engine::Graph;
use lightgraph_engine::ir::StateStorage;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

/// The live view option of the commands that render progressively.
#[derive(Args, Clone)]
pub struct TevArg {
    /// Stream the progressive image to a running tev (https://github.com/Tom94/tev), about
    /// once a second and at the end: at its default address 127.0.0.1:14158, or at HOST:PORT.
    /// A tev that is not there costs a warning, not the render.
    #[arg(long, num_args = 0..=1, default_missing_value = lightgraph::tev::DEFAULT_ADDRESS, value_name = "HOST:PORT")]
    pub tev: Option<String>,
}

impl TevArg {
    /// The live view of an image `name` of `size` pixels, if asked for.
    pub fn view(&self, name: &str, size: (u32, u32)) -> Option<LiveView> {
        LiveView::open(self.tev.as_deref(), name, size)
    }
}

/// The graph option of the commands that render one graph.
#[derive(Args, Clone)]
pub struct GraphArg {
    /// Graph: a built-in name or a .ron graph file [default: pt].
    #[arg(long)]
    pub graph: Option<String>,
}

impl GraphArg {
    /// The graph named, or the default.
    pub fn name(&self) -> &str {
        self.graph.as_deref().unwrap_or(DEFAULT_GRAPH)
    }
}

/// The options `compare` and `study` share, with one flag and default each; each command adds
/// its time, output folder and GPUs ([`CompareFlags::comparison`]).
#[derive(Args, Clone)]
pub struct CompareFlags {
    /// Count each run's set-up (pipeline creation, buffers, the first frame's compilation)
    /// on its budget; by default its clock starts after it and a warm-up frame (thrown away),
    /// and the set-up is reported beside it.
    #[arg(long)]
    pub setup_on_clock: bool,
    /// Error samples per decade of time (log-spaced from the first frame to the end, at
    /// least 12).
    #[arg(long, default_value_t = PER_DECADE, value_parser = count::<u32>, allow_negative_numbers = true)]
    pub per_decade: u32,
    /// Seed of the runs' random streams (must differ from the reference's).
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u32,
    #[command(flatten)]
    pub tev: TevArg,
    /// Exposure of the PNG previews in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

impl CompareFlags {
    /// The comparison of these options with each run's `time`, the output folder `out`
    /// (replaced with `force`) and the GPUs `gpus`.
    pub fn comparison(self, time: Duration, out: PathBuf, gpus: Option<String>, force: bool) -> Comparison {
        Comparison {
            budget: RunBudget {
                time,
                setup_on_clock: self.setup_on_clock,
            },
            per_decade: self.per_decade,
            seed: self.seed,
            tev: self.tev.tev,
            out,
            force,
            exposure: self.exposure,
            gpus,
        }
    }
}

/// A time as the command line takes it (`500ms`, `20s`, `2m`): the text of a default that a
/// library constant gives (clap keeps defaults as `'static` text; each value's is made once).
pub fn duration_text(time: Duration) -> &'static str {
    static TEXTS: Mutex<BTreeMap<Duration, &'static str>> = Mutex::new(BTreeMap::new());
    let mut texts = TEXTS.lock().unwrap_or_else(|e| e.into_inner());
    texts
        .entry(time)
        .or_insert_with(|| Box::leak(humantime::format_duration(time).to_string().into_boxed_str()))
}

/// Options every rendering command takes.
#[derive(Args, Clone)]
pub struct Common {
    /// Scene: a built-in name (see `lightgraph list`), a .ron scene file, or a bare .gltf/.glb
    /// file (its first camera or one framing it; a white background if it has no light)
    /// [default: cornell-mitsuba].
    #[arg(long)]
    pub scene: Option<String>,
    /// Image size WxH (default: the scene's).
    #[arg(long, value_parser = parse_resolution, allow_hyphen_values = true)]
    pub res: Option<(u32, u32)>,
    /// Samples per pixel in each frame [default: 1].
    #[arg(long, value_parser = count::<u32>, allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Maximum path length in segments (default: the scene's).
    #[arg(long, value_parser = count::<u32>, allow_negative_numbers = true)]
    pub max_path_length: Option<u32>,
    /// Override a graph constant, NAME=VALUE (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Folder scene files find their glTF assets in (also LIGHTGRAPH_ASSETS; default: the
    /// developers' shared scenes beside a checkout, where they exist).
    #[arg(long, env = "LIGHTGRAPH_ASSETS")]
    pub assets: Option<PathBuf>,
    /// GPU adapter: its index in `lightgraph list`, its PCI bus id, or text its name contains
    /// (also LIGHTGRAPH_ADAPTER).
    #[arg(long, env = "LIGHTGRAPH_ADAPTER")]
    pub adapter: Option<String>,
    /// Thread pool of regeneration and compaction layouts (overrides the layout's).
    #[arg(long, value_parser = count::<u64>, allow_negative_numbers = true)]
    pub threads: Option<u64>,
    /// Threads per workgroup (overrides the layout's).
    #[arg(long, value_parser = count::<u32>, allow_negative_numbers = true)]
    pub workgroup: Option<u32>,
    /// Item state between split kernels: soa or aos (overrides the layout's).
    #[arg(long, value_parser = parse_state)]
    pub state: Option<StateStorage>,
    /// Acceleration structure: bvh2 (binary, both children's boxes per node), cwbvh
    /// (compressed 8-wide, Ylitie et al. 2017), or auto: the one measured fastest in the
    /// layout (its `bvh` hint; cwbvh where it has none).
    #[arg(long, value_parser = parse_bvh_choice, default_value = "auto")]
    pub bvh: BvhChoice,
    /// Compile every scene feature (all light kinds, BSDFs, textures, ...) into the kernels
    /// instead of only those the scene uses.
    #[arg(long)]
    pub all_features: bool,
    /// Give every transient buffer memory of its own instead of sharing memory between
    /// buffers whose lifetimes do not overlap (to measure or rule out the sharing).
    #[arg(long)]
    pub separate_memory: bool,
    /// Use no subgroup operations even where the adapter has them: queue and compaction
    /// appends take one atomic per item instead of one per subgroup, and the operators use
    /// their workgroup-memory scans (to measure what subgroups buy).
    #[arg(long)]
    pub no_subgroups: bool,
    /// Keep wgpu's loop guards in the pass kernels (on) or leave them out (off): overrides
    /// the layout's `loop_guards` and the tuning profile's.
    #[arg(long, value_parser = parse_on_off)]
    pub loop_guards: Option<bool>,
    /// Bind at most BYTES of a scene buffer at once, below the adapter's limit: geometry
    /// larger than that is split over several buffers, as a scene too large for one storage
    /// binding is (to test or measure the split on a small scene).
    #[arg(long, value_name = "BYTES")]
    pub max_binding: Option<u64>,
    /// Tuning profile whose device knobs (loop guards, pool sizes, code variants that render
    /// the same image) the graph's named layouts take: auto (the adapter's built-in profile),
    /// none (the layouts as the graph writes them), a built-in profile's name, or a .ron
    /// profile of one's own (docs/tuning.md). The options above win over it.
    #[arg(long, value_parser = parse_tuning, default_value = "auto")]
    pub tuning: Tuning,
}

/// `--tuning`'s value, a profile file checked against the graphs it names.
fn parse_tuning(s: &str) -> Result<Tuning, String> {
    Tuning::parse(s, lightgraph::run::load_graph)
}

impl Common {
    /// The scene named, or the default.
    pub fn scene(&self) -> &str {
        self.scene.as_deref().unwrap_or(DEFAULT_SCENE)
    }

    /// These options as the library takes them.
    pub fn run_options(&self) -> RunOptions {
        RunOptions {
            scene: self.scene.clone(),
            res: self.res,
            spp: self.spp,
            max_path_length: self.max_path_length,
            sets: self.set.clone(),
            overrides: LayoutOverrides {
                threads: self.threads,
                workgroup_size: self.workgroup,
                state: self.state,
                all_features: self.all_features,
                separate_memory: self.separate_memory,
                no_subgroups: self.no_subgroups,
                loop_guards: self.loop_guards,
                max_binding: self.max_binding,
                tuning: self.tuning.clone(),
            },
            bvh: self.bvh,
            adapter: self.adapter.clone(),
        }
    }

    /// The run these options name with graph `graph`, layout `layout` (None: the graph's
    /// default) and `seed` ([`RunOptions::spec`]).
    pub fn spec(&self, graph: &str, layout: Option<&str>, seed: u32) -> RunSpec {
        self.run_options().spec(graph, layout, seed)
    }

    /// The session options of `graph` on `scene` with `seed` ([`RunOptions::options`]).
    pub fn options(&self, scene: &LoadedScene, graph: &Graph, seed: u32) -> Result<SessionOptions> {
        self.run_options().options(scene, graph, seed)
    }

    /// Takes the scene, resolution, samples per frame and constants of `options` (filled
    /// from a film or a reference).
    pub fn take(&mut self, options: RunOptions) {
        self.scene = options.scene;
        self.res = options.res;
        self.spp = options.spp;
        self.set = options.sets;
    }
}

/// Parses an `on` or `off` switch.
pub fn parse_on_off(s: &str) -> Result<bool, String> {
    match s.to_lowercase().as_str() {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}' is not on or off")),
    }
}

/// Parses `--bvh`: bvh2, cwbvh or auto.
pub fn parse_bvh_choice(s: &str) -> Result<BvhChoice, String> {
    BvhChoice::parse(s)
}

/// Parses `--state`.
pub fn parse_state(s: &str) -> Result<StateStorage, String> {
    match s.to_lowercase().as_str() {
        "soa" => Ok(StateStorage::SoA),
        "aos" => Ok(StateStorage::AoS),
        _ => Err(format!("'{s}' is not soa or aos")),
    }
}

/// Parses `--res WxH`: both sides at least 1.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| "it is not WxH, e.g. 640x480".to_string())?;
    let w = count(w).map_err(|e| format!("the width: {e}"))?;
    let h = count(h).map_err(|e| format!("the height: {e}"))?;
    Ok((w, h))
}

/// The mean of the reference at `path`, if any, checked to be `size` (for `--reference`).
pub fn reference_mean(path: Option<&PathBuf>, size: (u32, u32)) -> Result<Option<Vec<[f32; 3]>>> {
    let Some(path) = path else { return Ok(None) };
    let r = Film::read(path)?;
    r.check_size(path, size)?;
    Ok(Some(r.mean()))
}

/// With a signal's [`Interrupted`] error, says the command that goes on: this process's own
/// command line with `--resume` (and without `--force`, which resuming does not need); other
/// errors pass as they are.
pub fn with_resume_command(error: anyhow::Error) -> anyhow::Error {
    match error.downcast::<Interrupted>() {
        Ok(i) => {
            let mut words: Vec<String> = std::env::args_os()
                .skip(1)
                .map(|a| shell_word(Path::new(&a)))
                .filter(|w| w != "--force")
                .collect();
            if !words.iter().any(|w| w == "--resume") {
                words.push("--resume".into());
            }
            let what = format!("{}; `lightgraph {}` goes on", i.what, words.join(" "));
            Interrupted { what, ..i }.into()
        }
        Err(other) => other,
    }
}
