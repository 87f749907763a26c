//! lightgraph-engine: a generic frame-graph compiler and runtime for GPU compute.
//!
//! A graph (RON) names WGSL pass functions over items, the resources they read and write,
//! and the streams they emit into. The engine checks it, plans a layout (which passes are
//! fused into which kernel), generates one WGSL module per kernel, validates it with naga,
//! and runs frames through wgpu. It knows nothing about light transport.
//!
//! The stages, in order: parse and load ([`Graph::load`], [`load`]) → specialise and cull
//! ([`Graph::specialize`]) → plan a layout ([`Plan::new`]) → resolve sizes, lifetimes and
//! shared memory ([`resolve`]) → generate and validate WGSL ([`Program::compile`],
//! [`codegen`], [`collective`], [`radix`]) → execute ([`Instance::new`], [`Instance::run_frame`]).

pub mod access;
pub mod auto;
pub mod codegen;
pub mod collective;
pub mod error;
pub mod explain;
pub mod expr;
pub mod gpu;
pub mod graph;
pub mod ids;
pub mod internal;
pub mod ir;
pub mod load;
pub mod memory;
pub mod operator;
pub mod outline;
pub mod plan;
pub mod program;
pub mod radix;
pub mod reflect;
pub mod resolve;
pub mod runtime;
pub mod selfcheck;
pub mod specialize;
pub mod vfs;
pub mod wgsl;

pub use error::{Error, Location, Result};
pub use gpu::Gpu;
pub use graph::Graph;
pub use ir::ConstValue;
pub use plan::Plan;
pub use program::{Program, Specialization, Target};
pub use runtime::{FrameStats, Instance};
pub use vfs::{Layer, Vfs};
