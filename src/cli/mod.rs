//! The commands of the `lightgraph` binary, one module each, and the options they share.

pub mod args;
pub mod bench;
pub mod compare;
pub mod explain;
pub mod gpus;
pub mod list;
pub mod merge;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod operators;
pub mod reference;
pub mod render;
pub mod stress;
