//! The resolve stage: a scene's asset files found and imported, their textures, materials,
//! shapes (placed by `gltf_instances`), lights and camera merged into one scene model.

mod assets;
mod bare_gltf;
mod merge;
pub mod placement;

pub use assets::resolve_gltf;
pub use bare_gltf::scene_from_gltf;
