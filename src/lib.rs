//! lightgraph: a GPU progressive light-transport lab. Light-transport algorithms are frame
//! graphs of WGSL compute passes (`graphs/`, `passes/`, `shaders/`), compiled by the generic
//! engine (`lightgraph-engine`) into fused or split kernels, over scenes from
//! `lightgraph-scenes`.

// The command-line modules name this crate `lightgraph`, as the binary does.
extern crate self as lightgraph;

pub mod aov;
pub mod asset_catalog;
pub mod assets;
pub mod bench;
pub mod checkpoint;
pub mod cli;
#[cfg(feature = "mpi")]
pub mod cluster;
pub mod compare;
pub mod drive;
pub mod explain;
pub mod fetch;
pub mod film;
pub mod interrupt;
pub mod layout_cache;
pub mod live;
pub mod metrics;
pub mod multi;
pub mod output;
pub mod plot;
pub mod reference;
pub mod report;
pub mod run;
pub mod serve;
pub mod stress;
pub mod study;
pub mod tev;
pub mod tune;
pub mod tuning;
pub mod verify;
