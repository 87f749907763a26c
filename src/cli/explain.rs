//! `lightgraph explain`: kernels, schedule and resources of a graph's layouts
//! ([`lightgraph::explain`]).

use super::args::*;
use anyhow::Result;
use clap::Args;
use lightgraph::explain::{ExplainSpec, outline, report};
use std::path::PathBuf;

#[derive(Args)]
pub struct ExplainArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    /// Layout to explain (default: all of the graph's layouts).
    #[arg(long)]
    pub layout: Option<String>,
    /// Also write the graph as Graphviz DOT to this file.
    #[arg(long)]
    pub dot: Option<PathBuf>,
    /// Also write each kernel's generated WGSL into this folder.
    #[arg(long)]
    pub wgsl: Option<PathBuf>,
    /// Print only the graph's outline: its frame as loops over its items, each step the WGSL
    /// function and file that does it and what it reads and writes (no layout, no GPU).
    #[arg(long, conflicts_with_all = ["layout", "dot", "wgsl"])]
    pub outline: bool,
}

impl ExplainArgs {
    /// What these arguments ask to explain.
    pub fn spec(&self) -> ExplainSpec {
        ExplainSpec {
            options: self.common.run_options(),
            graph: self.graph.name().to_string(),
            layout: self.layout.clone(),
            dot: self.dot.clone(),
            wgsl: self.wgsl.clone(),
        }
    }
}

/// Prints [`report`], or with `--outline` [`outline`].
pub fn explain(args: ExplainArgs) -> Result<()> {
    let spec = args.spec();
    let text = if args.outline { outline(&spec)? } else { report(&spec)? };
    print!("{text}");
    Ok(())
}
