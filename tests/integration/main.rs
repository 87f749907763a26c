//! Integration tests of lightgraph on any wgpu adapter (lavapipe in CI): BVH traversal,
//! layouts, analytic radiance, the built-in scenes, the CLI and its errors.

mod analytic;
mod bpt;
mod bvh;
mod cli;
mod common;
mod composition;
mod gltf;
mod layouts;
mod reference;
mod scenes;
mod stress;
