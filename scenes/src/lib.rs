//! lightgraph-scenes: the scene model, RON scene files, glTF and Mitsuba import, validation,
//! BVH building and the GPU data the light-transport shaders read.
//!
//! A scene goes through four stages, each a folder whose modules import only the leaves and
//! earlier stages (`cargo xtask imports` checks that no modules import one another in a
//! circle); the leaves hold what every stage shares:
//!
//! | stage | modules | what it does |
//! |---|---|---|
//! | leaf | `error`, `model`, `gpu` | the scene error; the scene model (with its checks, textures, environment maps and glTF placements); the GPU's struct layouts |
//! | parse | `parse::scene_file`, `parse::gltf`, `parse::mitsuba`, `parse::tangents` | RON scene files, glTF assets (with MikkTSpace tangents) and Mitsuba XML read into the model |
//! | resolve | `resolve` | a scene's asset files found below the asset root, imported and merged into one model; glTF copies placed |
//! | build | `build::flatten`, `build::bvh`, `build::cwbvh`, `build::acceleration`, `build::alias`, `build::light_power`, `build::plastic` | primitives and lights, BVHs, the light-selection table and powers, coating tables |
//! | pack | `pack::compile`, `pack::materials`, `pack::textures`, `pack::resources`, `pack::split`, `pack::features` | the [`CompiledScene`] as the GPU reads it: its resources by name, split into bindings, and the shader features it uses |
//!
//! The entry points: [`parse_scene`], [`resolve_gltf`] (or [`scene_from_gltf`] for a bare glTF
//! file, [`mitsuba::load`] for a Mitsuba file), then [`CompiledScene::with_bvh`] and
//! [`CompiledScene::resources`].

pub mod build;
pub mod error;
pub mod gpu;
pub mod model;
pub mod pack;
pub mod parse;
pub mod resolve;

pub use build::acceleration::{TRACED_EXTENT, primitive_bounds};
pub use build::flatten::MAX_COORDINATE;
pub use build::light_power::light_power;
pub use build::{alias, bvh, cwbvh, plastic};
pub use error::SceneError;
pub use model::framing::default_camera;
pub use model::{environment, texture};
pub use pack::compile::CompiledScene;
pub use pack::{features, split};
pub use parse::scene_file::{parse_scene, read_grids};
pub use parse::{gltf, mitsuba};
pub use resolve::{resolve_gltf, scene_from_gltf};
