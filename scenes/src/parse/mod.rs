//! The parse stage: scene files read into the scene model (RON scene files, glTF assets,
//! Mitsuba XML), each error at its file and, where known, line and column.

pub mod gltf;
pub mod mitsuba;
pub mod scene_file;
pub mod tangents;
