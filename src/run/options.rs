//! A run's options and what they specialise: image size, samples, seed, constants, the
//! layout overrides and compilation target, and the constants and preprocessor flags a
//! graph is specialised with for a scene and a device.

use crate::run::checks;
use crate::run::scene::LoadedScene;
use anyhow::{Result, anyhow};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Gpu, Graph, Specialization};
use lightgraph_scenes::model::{MisHeuristic, RussianRoulette, Scene};
use std::collections::{BTreeMap, BTreeSet};

/// Image size, sampling and seed of a session.
#[derive(Debug, Clone, PartialEq)]
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
#[derive(Debug, Clone, Default, PartialEq)]
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
    /// Bind at most this many bytes of a scene buffer at once (`--max-binding`), below the
    /// adapter's limit: a small scene's geometry splits as a large one's does.
    pub max_binding: Option<u64>,
    /// The tuning profile whose device knobs the graph's named layouts take (`--tuning`).
    pub tuning: crate::tuning::Tuning,
}

impl LayoutOverrides {
    /// The compilation target of `gpu` with these overrides.
    pub fn target(&self, gpu: &Gpu) -> lightgraph_engine::Target {
        self.on_target(gpu.target())
    }

    /// `target` (a GPU's, or the default without one) with these overrides.
    pub fn on_target(&self, target: lightgraph_engine::Target) -> lightgraph_engine::Target {
        let target = lightgraph_engine::Target {
            alias_transients: !self.separate_memory,
            ..target
        };
        match self.no_subgroups {
            true => target.without_subgroups(),
            false => target,
        }
    }
}

impl LayoutOverrides {
    /// The layout `layout` (`decl`) of `graph` as it compiles on `gpu` (None: no GPU): the
    /// tuning profile's knobs, then these overrides.
    pub fn resolve(&self, gpu: Option<&Gpu>, graph: &Graph, layout: &str, decl: LayoutDecl) -> LayoutDecl {
        self.apply(self.tuning.apply(gpu, graph, layout, decl))
    }

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
pub(crate) const FLOAT32_ATOMIC_FLAG: &str = "FLOAT32_ATOMIC";

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
