//! What names a run ([`RunSpec`]: scene, graph, layout, options, constants, seed, frames) and
//! the run it loads ([`Run`]: the graph, its layout, the scene and the checked options, the
//! measured constants once measured), from which every front end makes its sessions.

use crate::run::checks;
use crate::run::checks::image_past_binding_limit;
use crate::run::graph::{graph_handles_scene, load_graph, named_layout};
use crate::run::measure::measure_constants;
use crate::run::options::{LayoutOverrides, SessionOptions, device_flags, kernel_flags, parse_sets, specialization};
use crate::run::scene::{BvhChoice, LoadedScene, Scenes, load_scene_with};
use crate::run::session::Session;
use anyhow::{Result, anyhow, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Gpu, Graph, Program};
use lightgraph_scenes::bvh::BvhKind;
use std::sync::Arc;

/// The scene rendered when none is named.
pub const DEFAULT_SCENE: &str = "cornell-mitsuba";
/// The graph used when none is named.
pub const DEFAULT_GRAPH: &str = "pt";
/// The seed of a run's random streams when none is given.
pub const DEFAULT_SEED: u32 = 1;
/// The layout name that asks a front end to measure the graph's layouts and take the fastest.
pub const AUTO_LAYOUT: &str = "auto";

/// Everything that names a run, before anything is loaded: what the command line's flags and
/// the Python module's keyword arguments both become.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// Scene: a built-in name, a .ron scene file, a bare .gltf/.glb or a Mitsuba .xml file.
    pub scene: String,
    /// Graph: a built-in name or a .ron graph file.
    pub graph: String,
    /// Layout name (None: the graph's default; [`AUTO_LAYOUT`]: measured by the front end).
    pub layout: Option<String>,
    /// Image size (None: the scene's).
    pub res: Option<(u32, u32)>,
    /// Samples per pixel in each frame.
    pub spp: u32,
    /// Longest path in segments (None: the scene's).
    pub max_path_length: Option<u32>,
    /// Constant settings, `NAME=VALUE`, checked against the graph when it is loaded.
    pub sets: Vec<String>,
    /// Layout option overrides and compilation switches.
    pub overrides: LayoutOverrides,
    /// The acceleration structure.
    pub bvh: BvhChoice,
    /// Seed of the random streams.
    pub seed: u32,
    /// Frame index of the run's first frame.
    pub first_frame: u64,
    /// GPU adapter: an index, a PCI bus id or text of its name (None: the default).
    pub adapter: Option<String>,
}

impl Default for RunSpec {
    fn default() -> RunSpec {
        RunSpec {
            scene: DEFAULT_SCENE.to_string(),
            graph: DEFAULT_GRAPH.to_string(),
            layout: None,
            res: None,
            spp: 1,
            max_path_length: None,
            sets: Vec::new(),
            overrides: LayoutOverrides::default(),
            bvh: BvhChoice::default(),
            seed: DEFAULT_SEED,
            first_frame: 0,
            adapter: None,
        }
    }
}

impl RunSpec {
    /// Whether the layout is to be measured ([`AUTO_LAYOUT`]).
    pub fn auto_layout(&self) -> bool {
        self.layout.as_deref() == Some(AUTO_LAYOUT)
    }

    /// The session options for `scene` rendered by `graph`; the image size is checked to fit
    /// before anything is allocated, and the settings to be constants of the graph.
    pub fn options(&self, scene: &LoadedScene, graph: &Graph) -> Result<SessionOptions> {
        let (width, height) = self.res.unwrap_or(scene.scene.resolution);
        let spp = self.spp;
        checks::image_fits(width, height, spp).map_err(|e| anyhow!("--res {width}x{height} with --spp {spp}: {e}"))?;
        graph_handles_scene(graph, scene).map_err(|e| anyhow!("{}: {e}", self.scene))?;
        let mut constants = parse_sets(&self.sets, graph, "--set ")?;
        if let Some(n) = self.max_path_length {
            constants.insert("MAX_PATH_LENGTH".into(), ConstValue::U32(n));
        }
        Ok(SessionOptions {
            width,
            height,
            samples_per_frame: spp,
            seed: self.seed,
            constants,
            layout: self.overrides.clone(),
        })
    }
}

/// The options of runs as a front end gives them, before defaults: the scene, image size,
/// samples per frame and constants left out may come from a film or a reference
/// ([`RunOptions::from_film`], [`RunOptions::from_reference`]); [`RunOptions::spec`] names a
/// run of them.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Scene (None: [`DEFAULT_SCENE`]).
    pub scene: Option<String>,
    /// Image size (None: the scene's).
    pub res: Option<(u32, u32)>,
    /// Samples per pixel in each frame (None: 1).
    pub spp: Option<u32>,
    /// Longest path in segments (None: the scene's).
    pub max_path_length: Option<u32>,
    /// Constant settings, `NAME=VALUE`.
    pub sets: Vec<String>,
    /// Layout option overrides and compilation switches.
    pub overrides: LayoutOverrides,
    /// The acceleration structure.
    pub bvh: BvhChoice,
    /// GPU adapter (None: the default).
    pub adapter: Option<String>,
}

impl RunOptions {
    /// The scene named, or the default.
    pub fn scene(&self) -> &str {
        self.scene.as_deref().unwrap_or(DEFAULT_SCENE)
    }

    /// The run of these options with graph `graph`, layout `layout` (None: the graph's
    /// default) and `seed`.
    pub fn spec(&self, graph: &str, layout: Option<&str>, seed: u32) -> RunSpec {
        RunSpec {
            scene: self.scene().to_string(),
            graph: graph.to_string(),
            layout: layout.map(str::to_string),
            res: self.res,
            spp: self.spp.unwrap_or(1),
            max_path_length: self.max_path_length,
            sets: self.sets.clone(),
            overrides: self.overrides.clone(),
            bvh: self.bvh,
            seed,
            first_frame: 0,
            adapter: self.adapter.clone(),
        }
    }

    /// The session options of `graph` on `scene` with `seed` ([`RunSpec::options`]).
    pub fn options(&self, scene: &LoadedScene, graph: &Graph, seed: u32) -> Result<SessionOptions> {
        self.spec(&graph.name, None, seed).options(scene, graph)
    }
}

/// A loaded run: the graph in a layout, the scene with the layout's BVH and the checked
/// options. Its sessions ([`Run::session`]) compile it for one GPU each.
pub struct Run {
    /// What it was loaded from.
    pub spec: RunSpec,
    /// The graph.
    pub graph: Graph,
    /// The layout's name.
    pub layout: String,
    /// The layout.
    pub decl: LayoutDecl,
    /// The scene, with the BVH the layout asks for (shared with the other runs of a command
    /// that loaded it once: [`Run::load_in`]).
    pub scene: Arc<LoadedScene>,
    /// The session options (measured constants among the constants once measured).
    pub options: SessionOptions,
    /// The program of the run's layout compiled already, where the tuner measured it
    /// ([`Run::take_tuned`]): the run's sessions instantiate it instead of compiling again.
    compiled: Option<Compiled>,
}

/// A program compiled for a run, with what it was compiled for: a session takes it only while
/// the run still names all of it.
struct Compiled {
    /// The layout's name and the layout.
    layout: (String, LayoutDecl),
    /// The scene (the run's own, not one loaded again for another BVH).
    scene: Arc<LoadedScene>,
    /// The options, measured constants included.
    options: SessionOptions,
    /// The adapter ([`Gpu::describe`]), whose target and features the program was compiled for.
    adapter: String,
    /// The program.
    program: Program,
}

impl Run {
    /// Loads the graph, its layout (the default one while [`RunSpec::auto_layout`], until the
    /// front end chooses), the scene and the options `spec` names, in that order (so the
    /// errors of the inputs come first).
    pub fn load(spec: &RunSpec) -> Result<Run> {
        let graph = load_graph(&spec.graph)?;
        let auto = spec.auto_layout();
        let (layout, decl) = named_layout(&graph, spec.layout.as_deref().filter(|_| !auto))?;
        let kind = match auto {
            true => spec.bvh.or_default(),
            false => spec.bvh.for_layout(&layout, &decl)?,
        };
        let scene = Arc::new(load_scene_with(&spec.scene, kind)?);
        Run::with_scene(spec, graph, (layout, decl), scene)
    }

    /// [`Run::load`] of a run with a named layout (or the graph's default) whose scene comes
    /// from `scenes` (`spec`'s scene, loaded once per BVH kind among the runs of a command).
    pub fn load_in(spec: &RunSpec, scenes: &mut Scenes) -> Result<Run> {
        let graph = load_graph(&spec.graph)?;
        let (layout, decl) = named_layout(&graph, spec.layout.as_deref())?;
        let kind = scenes.load_for(spec.bvh, &layout, &decl)?;
        let scene = scenes.shared(kind);
        Run::with_scene(spec, graph, (layout, decl), scene)
    }

    /// The run `spec` names of `graph` in the layout `decl` (called `layout`) on `scene`, all
    /// loaded already (the scene with the layout's BVH); checks the options.
    pub fn with_scene(
        spec: &RunSpec,
        graph: Graph,
        (layout, decl): (String, LayoutDecl),
        scene: Arc<LoadedScene>,
    ) -> Result<Run> {
        let options = spec.options(&scene, &graph)?;
        Ok(Run {
            spec: spec.clone(),
            graph,
            layout,
            decl,
            scene,
            options,
            compiled: None,
        })
    }

    /// [`Run::load`] of a run with a named layout: `how` (the option or call that shares the
    /// run) is in the error when the layout is `auto`, which measures on one GPU.
    pub fn load_named(spec: &RunSpec, how: &str) -> Result<Run> {
        if spec.auto_layout() {
            bail!("--layout auto measures layouts on one GPU; name a layout with {how}");
        }
        Run::load(spec)
    }

    /// The run in the layout called `name` instead, its scene loaded again when the layout's
    /// BVH (as the spec chooses it) is another.
    pub fn relayout(&mut self, name: &str) -> Result<()> {
        let decl = self.graph.layout(name)?.clone();
        self.load_bvh(self.spec.bvh.for_layout(name, &decl)?)?;
        (self.layout, self.decl) = (name.to_string(), decl);
        Ok(())
    }

    /// Loads the scene again with the BVH `bvh` unless it has it.
    pub fn load_bvh(&mut self, bvh: BvhKind) -> Result<()> {
        if bvh != self.bvh() {
            self.scene = Arc::new(load_scene_with(&self.spec.scene, bvh)?);
        }
        Ok(())
    }

    /// The BVH the scene was loaded with.
    pub fn bvh(&self) -> BvhKind {
        self.scene.compiled.bvh_kind
    }

    /// Puts the graph's measured constants (those the options do not give) into the options,
    /// measured once on `gpu`, so that every session and GPU of the run, and its film's
    /// settings, share one measurement.
    pub fn measure(&mut self, gpu: &Gpu) -> Result<()> {
        let measured = measure_constants(
            gpu,
            &self.graph,
            &self.layout,
            self.decl.clone(),
            &self.scene,
            &self.options,
        )?;
        self.options.constants.extend(measured);
        Ok(())
    }

    /// [`Run::measure`] on the adapter `adapter` names, opened only where something is left
    /// to measure.
    pub fn measure_on(&mut self, adapter: Option<&str>) -> Result<()> {
        if self.measured() {
            return Ok(());
        }
        self.measure(&Gpu::new(adapter)?)
    }

    /// Whether every measured constant of the graph has its value in the options.
    pub fn measured(&self) -> bool {
        let constants = &self.options.constants;
        self.graph.measured.keys().all(|name| constants.contains_key(name))
    }

    /// Takes the layout `name` (`decl`) that the tuner measured on `gpu` with this run's scene
    /// and options, and the program its measurement compiled: the graph's measured constants
    /// that program holds go into the options (the trial measured them in this layout), and
    /// the run's sessions on `gpu` instantiate the program instead of compiling it again.
    pub fn take_tuned(&mut self, gpu: &Gpu, (name, decl): (String, LayoutDecl), program: Option<Program>) {
        self.compiled = program.map(|program| {
            for measured in self.graph.measured.keys() {
                if let Some(value) = program.constants().get(measured) {
                    self.options.constants.entry(measured.clone()).or_insert(*value);
                }
            }
            Compiled {
                layout: (name.clone(), decl.clone()),
                scene: self.scene.clone(),
                options: self.options.clone(),
                adapter: gpu.describe(),
                program,
            }
        });
        (self.layout, self.decl) = (name, decl);
    }

    /// The program compiled already for the run as it is now on `gpu`, if any.
    fn compiled_for(&self, gpu: &Gpu) -> Option<&Program> {
        let c = self.compiled.as_ref()?;
        let same = (&c.layout.0, &c.layout.1) == (&self.layout, &self.decl)
            && Arc::ptr_eq(&c.scene, &self.scene)
            && c.options == self.options
            && c.adapter == gpu.describe();
        same.then_some(&c.program)
    }

    /// The run compiled and instantiated on `gpu`, at the run's first frame (the program the
    /// tuner compiled for it, where it still fits, instantiated without compiling again).
    pub fn session<'g>(&self, gpu: &'g Gpu) -> Result<Session<'g>> {
        let size = (self.options.width, self.options.height);
        let mut session = match self.compiled_for(gpu) {
            Some(program) => Session::of_program(
                gpu,
                &self.graph,
                (&self.layout, self.decl.clone()),
                program.clone(),
                &self.scene,
                self.options.clone(),
            )
            .map_err(|e| image_past_binding_limit(e, &self.graph, size))?,
            None => self.session_in(gpu, &self.layout, &self.decl)?,
        };
        session.first_frame =
            u32::try_from(self.spec.first_frame).map_err(|_| anyhow!("the first frame is past 2^32"))?;
        Ok(session)
    }

    /// The run's program for `gpu`'s target and features, or without a GPU for the default
    /// target and no optional feature, compiled without measuring: measured constants the
    /// options do not give keep their defaults (what `explain` shows without a GPU).
    pub fn compile(&self, gpu: Option<&Gpu>) -> Result<Program> {
        let (device, target) = gpu.map(|g| (device_flags(g), g.target())).unwrap_or_default();
        let flags = kernel_flags(device, &self.scene, self.options.layout.all_features);
        let spec = specialization(&self.graph, &self.scene.scene, &self.options, flags);
        let decl = self
            .options
            .layout
            .resolve(gpu, &self.graph, &self.layout, self.decl.clone());
        let target = self.options.layout.on_target(target);
        lightgraph_engine::compile(&self.graph, &self.layout, &decl, &spec, &target)
            .map_err(|e| image_past_binding_limit(e.into(), &self.graph, (self.options.width, self.options.height)))
    }

    /// The run compiled and instantiated on `gpu` in the layout `decl` (called `layout`)
    /// instead of its own, at frame 0: a layout the tuner measures. The graph's measured
    /// constants that the options do not give are measured first, in that layout.
    pub fn session_in<'g>(&self, gpu: &'g Gpu, layout: &str, decl: &LayoutDecl) -> Result<Session<'g>> {
        Session::with_layout(
            gpu,
            &self.graph,
            layout,
            decl.clone(),
            &self.scene,
            self.options.clone(),
        )
        .map_err(|e| image_past_binding_limit(e, &self.graph, (self.options.width, self.options.height)))
    }
}
