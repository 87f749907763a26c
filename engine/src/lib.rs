//! lightgraph-engine: a generic frame-graph compiler and runtime for GPU compute.
//!
//! A graph (RON) names WGSL pass functions over items, the resources they read and write,
//! and the streams they emit into. The engine checks it, plans a layout (which passes are
//! fused into which kernel), generates one WGSL module per kernel, validates it with naga,
//! and runs frames through wgpu. It knows nothing about light transport.
//!
//! The stages run in this order, each module importing only modules of earlier stages and of
//! its own (without a cycle); the leaf modules hold what every stage shares
//! (`tests/stage_order.rs` checks both against this table, and that `docs/graphs.md` repeats
//! it):
//!
//! | stage | modules | what it does |
//! |---|---|---|
//! | leaf | `error`, `expr`, `ids`, `ir`, `limits`, `vfs`, `wgsl` | errors, count expressions, typed indices, the RON declarations, shared limits and the target, the file system, WGSL sources (`#if` flags, naga with a source map) |
//! | load | `operator`, `load`, `extend`, `hooks`, `item_fields`, `graph` | the graph file with its bases, catalogs and includes, every name checked; the hooks it replaces and the fields it adds to items; chains and phases |
//! | specialise | `derive`, `specialize` | the constants' values; the reads and writes that passes leave out, derived with naga from the WGSL with the flags; then culling: the live graph |
//! | plan | `plan`, `auto` | a layout's kernels, roots and schedule, its fusion checked; every legal layout |
//! | reflect | `reflect`, `access` | the sources compiled together with naga: item words, what each pass touches of its item, each pass checked against its declaration |
//! | resolve | `memory`, `scratch`, `resolve` | bindings, control words, sizes, domains, pools, capacities, operator scratch, lifetimes and shared memory |
//! | generate | `codegen`, `internal`, `scan`, `radix`, `collective`, `program` | one WGSL module per kernel (passes, the engine's own, the operators'), validated with naga |
//! | run | `gpu`, `runtime` | the device, buffers, pipelines and frames |
//! | consumers | `explain`, `outline`, `selfcheck` | reports of programs and graphs, the operators' checks on a device |
//!
//! The entry points: [`Graph::load`] (load, then the default constants' live view),
//! [`Graph::layout`], [`compile`] (the one compile entry: a graph, a layout, a specialisation
//! and a target; it specialises, plans, reflects, resolves and generates), [`Instance::new`]
//! and [`Instance::run_frame`]; [`auto::legal_layouts`] lists the layouts `--layout auto`
//! measures. Within a compile the
//! resolve stage begins before reflection ([`resolve::Resolved::for_reflection`]: binding
//! numbers and control words, from the plan alone), since the prelude every source is compiled
//! with declares them.

pub mod access;
pub mod auto;
pub mod codegen;
pub mod collective;
pub mod derive;
pub mod error;
pub mod explain;
pub mod expr;
pub mod extend;
pub mod gpu;
pub mod graph;
pub mod hooks;
pub mod ids;
pub mod internal;
pub mod ir;
pub mod item_fields;
pub mod limits;
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
pub mod scan;
pub mod scratch;
pub mod selfcheck;
pub mod specialize;
pub mod vfs;
pub mod wgsl;

pub use error::{Error, Location, Result};
pub use gpu::Gpu;
pub use graph::Graph;
pub use ir::ConstValue;
pub use limits::Target;
pub use plan::Plan;
pub use program::{Program, Specialization, compile, compiles_on_this_thread};
pub use runtime::{FrameStats, Instance};
pub use vfs::{Layer, Vfs};
