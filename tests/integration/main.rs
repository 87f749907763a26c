//! Integration tests of lightgraph on any wgpu adapter (lavapipe in CI): BVH traversal,
//! layouts, analytic radiance, the built-in scenes, the CLI and its errors.

mod analytic;
mod aov;
mod assets;
mod bpt;
mod bsdf;
mod bvh;
mod chi2;
mod cli;
mod common;
mod composition;
mod docs;
mod frames;
mod gltf;
mod interrupt;
mod layouts;
mod lights;
mod lost_work;
mod mitsuba;
mod options;
mod photon_query;
mod pm;
mod probe;
mod reference;
mod resolve;
mod scenes;
mod shading;
mod shards;
mod specialize;
mod stress;
mod study;
mod subgroups;
mod tev;
mod textures;
mod vcm;
mod verify;
