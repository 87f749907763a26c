//! The pack stage (issue 58's "upload"): the built scene packed as the GPU reads it
//! ([`crate::gpu`]'s layouts): the compiled scene, its materials and textures, its resources
//! by name (which the app uploads), their split into bindings, and the shader features the
//! scene uses.

pub mod compile;
pub mod features;
pub mod materials;
pub mod media;
pub mod resources;
pub mod split;
pub mod textures;
