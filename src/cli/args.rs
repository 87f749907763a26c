//! Options shared by the commands: scene, graph, resolution, constants, layout overrides.

use super::checks::{self, count};
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use lightgraph::compare::RunSpec;
use lightgraph::reference::Reference;
use lightgraph::render::{LayoutOverrides, LoadedScene, SessionOptions, load_graph};
use lightgraph::tev::LiveView;
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::ir::StateStorage;
use lightgraph_engine::{ConstValue, Gpu, Graph, Plan};
use lightgraph_scenes::bvh::BvhKind;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The scene rendered when none is named.
pub const DEFAULT_SCENE: &str = "cornell-mitsuba";
/// The graph used when none is named.
pub const DEFAULT_GRAPH: &str = "pt";

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
        let address = self.tev.as_deref()?;
        Some(LiveView::connect(address, name, size, Duration::from_secs(1)))
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
    /// Folder scene files find their glTF assets in (also LIGHTGRAPH_ASSETS; default:
    /// ../shared/scenes when it exists).
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
    /// the layout's `loop_guards`, which is off in the layouts measured faster without them.
    #[arg(long, value_parser = parse_on_off)]
    pub loop_guards: Option<bool>,
}

impl Common {
    /// The scene named, or the default.
    pub fn scene(&self) -> &str {
        self.scene.as_deref().unwrap_or(DEFAULT_SCENE)
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

/// Parses `--bvh`.
pub fn parse_bvh(s: &str) -> Result<BvhKind, String> {
    match s.to_lowercase().as_str() {
        "bvh2" => Ok(BvhKind::Bvh2),
        "cwbvh" => Ok(BvhKind::Cwbvh),
        _ => Err(format!("'{s}' is not bvh2 or cwbvh")),
    }
}

/// `--bvh`: a BVH kind, or `auto` (none named): the layout's measured choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BvhChoice(pub Option<BvhKind>);

/// Parses `--bvh` with `auto`.
pub fn parse_bvh_choice(s: &str) -> Result<BvhChoice, String> {
    match s.to_lowercase().as_str() {
        "auto" => Ok(BvhChoice(None)),
        _ => parse_bvh(s)
            .map(|k| BvhChoice(Some(k)))
            .map_err(|e| format!("{e} or auto")),
    }
}

impl BvhChoice {
    /// The BVH of a layout: the one named, else the layout's `bvh` hint (graphs/*.ron, from
    /// measurements on an H100: docs/performance.md), else the CWBVH.
    pub fn for_layout(self, name: &str, decl: &LayoutDecl) -> Result<BvhKind> {
        if let Some(kind) = self.0 {
            return Ok(kind);
        }
        match decl.hints.get("bvh") {
            None => Ok(BvhKind::Cwbvh),
            Some(hint) => parse_bvh(hint).map_err(|e| anyhow!("layout '{name}': its hint bvh: {e}")),
        }
    }

    /// The BVH when no layout decides (`--layout auto` measures layouts on one scene).
    pub fn or_default(self) -> BvhKind {
        self.0.unwrap_or(BvhKind::Cwbvh)
    }
}

/// Scenes loaded with each BVH kind asked for, once each (layouts of one command may want
/// different kinds).
pub struct Scenes {
    name: String,
    loaded: Vec<(BvhKind, LoadedScene)>,
}

impl Scenes {
    /// None loaded yet of scene `name`.
    pub fn new(name: &str) -> Scenes {
        Scenes {
            name: name.to_string(),
            loaded: Vec::new(),
        }
    }

    /// Loads the scene with the BVH `bvh` gives layout `name` (`decl`), unless it is loaded
    /// already; returns that BVH.
    pub fn load_for(&mut self, bvh: BvhChoice, name: &str, decl: &LayoutDecl) -> Result<BvhKind> {
        let kind = bvh.for_layout(name, decl)?;
        if !self.loaded.iter().any(|(k, _)| *k == kind) {
            self.loaded
                .push((kind, lightgraph::render::load_scene_with(&self.name, kind)?));
        }
        Ok(kind)
    }

    /// The longest time one of the loads took (parsing and the BVH build), in seconds.
    pub fn load_seconds(&self) -> f64 {
        self.loaded.iter().map(|(_, s)| s.load_seconds).fold(0.0, f64::max)
    }

    /// The scene with `kind`, which [`Scenes::load_for`] loaded.
    pub fn get(&self, kind: BvhKind) -> &LoadedScene {
        &self
            .loaded
            .iter()
            .find(|(k, _)| *k == kind)
            .expect("loaded before use")
            .1
    }
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

/// Parses `NAME=VALUE` entries as constants of `graph`, each of its type; an error starts
/// with `flag` and the entry (`flag` is `--set ` for `--set`, `--runs @` for a run's own).
pub fn parse_sets(sets: &[String], graph: &Graph, flag: &str) -> Result<BTreeMap<String, ConstValue>> {
    let mut out = BTreeMap::new();
    for s in sets {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| anyhow!("{flag}{s}: expected NAME=VALUE"))?;
        let v = checks::constant(graph, name.trim(), value).map_err(|e| anyhow!("{flag}{s}: {e}"))?;
        out.insert(name.trim().to_string(), v);
    }
    Ok(out)
}

/// The session options the shared flags give for `scene` rendered by `graph`, with the seed
/// of the command; the image size is checked to fit before anything is allocated.
pub fn options(common: &Common, scene: &LoadedScene, graph: &Graph, seed: u32) -> Result<SessionOptions> {
    let (width, height) = common.res.unwrap_or(scene.scene.resolution);
    let spp = common.spp.unwrap_or(1);
    checks::image_fits(width, height, spp).map_err(|e| anyhow!("--res {width}x{height} with --spp {spp}: {e}"))?;
    let mut constants = parse_sets(&common.set, graph, "--set ")?;
    if let Some(n) = common.max_path_length {
        constants.insert("MAX_PATH_LENGTH".into(), ConstValue::U32(n));
    }
    let layout = LayoutOverrides {
        threads: common.threads,
        workgroup_size: common.workgroup,
        state: common.state,
        all_features: common.all_features,
        separate_memory: common.separate_memory,
        no_subgroups: common.no_subgroups,
        loop_guards: common.loop_guards,
    };
    Ok(SessionOptions {
        width,
        height,
        samples_per_frame: spp,
        seed,
        constants,
        layout,
    })
}

/// The layout called `name`, or the graph's default.
pub fn named_layout(graph: &Graph, name: Option<&str>) -> Result<(String, LayoutDecl)> {
    Ok(match name {
        Some(name) => (name.to_string(), Plan::new(graph, name)?.layout),
        None => (
            graph.default_layout.clone(),
            graph.layouts[&graph.default_layout].clone(),
        ),
    })
}

/// Checks that a reference has the image size of the render compared with it.
/// The mean of the reference at `path`, if any, checked to be `size` (for `--reference`).
pub fn reference_mean(path: Option<&PathBuf>, size: (u32, u32)) -> Result<Option<Vec<[f32; 3]>>> {
    let Some(path) = path else { return Ok(None) };
    let r = Reference::read(path)?;
    check_size(&r, path, size)?;
    Ok(Some(r.mean()))
}

pub fn check_size(reference: &Reference, path: &Path, size: (u32, u32)) -> Result<()> {
    if reference.size != size {
        bail!(
            "{}: the reference is {}x{}, the render {}x{}; pass --res {}x{} or make a reference at this size",
            path.display(),
            reference.size.0,
            reference.size.1,
            size.0,
            size.1,
            reference.size.0,
            reference.size.1
        );
    }
    Ok(())
}

/// Puts the graph's measured constants (those `opts` does not give) into `opts`, measured
/// once on the GPU `adapter`, so that every session and GPU of a run, and the film's settings,
/// share one measurement (see [`lightgraph::render::measure_constants`]).
pub fn measure_into(
    opts: &mut SessionOptions,
    graph: &Graph,
    (layout, decl): (&str, &LayoutDecl),
    scene: &LoadedScene,
    adapter: Option<&str>,
) -> Result<()> {
    if graph.measured.keys().all(|name| opts.constants.contains_key(name)) {
        return Ok(());
    }
    let gpu = Gpu::new(adapter)?;
    let measured = lightgraph::render::measure_constants(&gpu, graph, layout, decl.clone(), scene, opts)?;
    opts.constants.extend(measured);
    Ok(())
}

/// A number with an SI prefix and a trailing space, e.g. "1.28 G".
pub fn si(v: f64) -> String {
    match v {
        v if v >= 1e9 => format!("{:.2} G", v / 1e9),
        v if v >= 1e6 => format!("{:.2} M", v / 1e6),
        v if v >= 1e3 => format!("{:.2} k", v / 1e3),
        v => format!("{v:.1} "),
    }
}

/// Checks that `scene` (named by option `flag`) is a file or a built-in scene (loading it, and
/// the errors of its content, come in its turn).
pub fn find_scene(scene: &str, flag: &str) -> Result<()> {
    if !Path::new(scene).is_file() {
        lightgraph::assets::scene_text(scene).map_err(|e| anyhow!("{flag}: {e}"))?;
    }
    Ok(())
}

/// The estimators a list of `graph[:Layout][@NAME=VALUE...]` names (option `flag`), each
/// graph, named layout and constant checked, none named twice.
pub fn estimator_specs(list: &str, flag: &str) -> Result<Vec<RunSpec>> {
    if list.split(',').all(|s| s.trim().is_empty()) {
        bail!("{flag} names no estimator; give graphs or graph:Layout pairs, e.g. pt,bpt-lvc:LVC-BPTmk");
    }
    let specs = RunSpec::parse_list(list)?;
    for (i, spec) in specs.iter().enumerate() {
        if specs[..i].contains(spec) {
            bail!("{flag} names {spec} twice");
        }
        let graph = load_graph(&spec.graph).with_context(|| format!("{flag} {spec}"))?;
        if let Some(layout) = &spec.layout {
            named_layout(&graph, Some(layout)).with_context(|| format!("{flag} {spec}"))?;
        }
        parse_sets(&spec.sets, &graph, &format!("{flag} @"))?;
    }
    Ok(specs)
}
