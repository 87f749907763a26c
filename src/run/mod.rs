//! One run, the owner of what every front end renders: a [`RunSpec`] (scene, graph, layout,
//! options, constants, seed, first frame) loads a [`Run`] (graph, layout, scene, checked
//! options, measured constants), whose [`Session`]s compile and instantiate it on a GPU and
//! render it. `render`, `reference`, `--gpus`, `--mpi` and Python build runs; `compare`,
//! `study`, `verify` and `bench` load scenes and graphs and make sessions through the same
//! modules.
//!
//! - [`checks`]: option values checked before any work (counts, times, image sizes, constants).
//! - [`scene`]: loading a scene with the BVH a layout asks for.
//! - [`graph`]: loading a graph and naming its layout.
//! - [`options`]: session options and the specialisation they and the scene imply.
//! - [`spec`]: [`RunSpec`] and [`Run`].
//! - [`measure`]: preparing a compilation and measuring measured constants.
//! - [`session`]: a run on one GPU, frame after frame.

pub mod checks;
pub mod graph;
pub mod measure;
pub mod options;
pub mod scene;
pub mod session;
pub mod spec;

pub use graph::{graph_handles_scene, load_graph, named_layout};
pub use measure::measure_constants;
pub use options::{
    LayoutOverrides, SessionOptions, device_flags, kernel_flags, parse_sets, scene_constants, specialization,
};
pub use scene::{BvhChoice, LoadedScene, Scenes, load_scene, load_scene_with, parse_bvh};
pub use session::{Accumulation, BATCH_TIME, Image, Session};
pub use spec::{AUTO_LAYOUT, DEFAULT_GRAPH, DEFAULT_SCENE, DEFAULT_SEED, Run, RunOptions, RunSpec};
