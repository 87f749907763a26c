//! `lightgraph compare`: estimators and layouts against a reference, error against time
//! ([`lightgraph::compare::render`]).

use super::args::*;
use anyhow::Result;
use clap::Args;
use lightgraph::compare::html::html_path;
use lightgraph::compare::render::{COMPARE_OUT, COMPARE_TIME, CompareSpec};
use std::path::PathBuf;
use std::time::Duration;

#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    /// Runs to compare, comma-separated `graph:layout` (or `graph` for its default layout),
    /// e.g. pt:NaivePTsk,pt:RegenerationPTsk.
    #[arg(long)]
    pub runs: String,
    /// The reference EXR (from `lightgraph reference`); the scene, resolution and constants
    /// default to its own.
    #[arg(long)]
    pub reference: PathBuf,
    /// Wall-clock budget of each run.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = duration_text(COMPARE_TIME))]
    pub time: Duration,
    /// Continue the comparison in --out (after a signal stopped it): the runs whose curves
    /// are there are not rendered again; its settings must be these.
    #[arg(long)]
    pub resume: bool,
    /// The run the others are measured against [default: the first].
    #[arg(long)]
    pub baseline: Option<String>,
    #[command(flatten)]
    pub flags: CompareFlags,
    /// Output folder: curves.csv, rmse_vs_time.png, summary.md, report.html and each run's EXR
    /// and PNG.
    #[arg(long, default_value = COMPARE_OUT)]
    pub out: PathBuf,
    /// Write into a --out that holds an earlier run's comparison (its curves, summary and images), replacing them.
    #[arg(long)]
    pub force: bool,
    /// Run on several GPUs of one model at once, each taking the next run when its last one
    /// ends (every run still has `--time` on one GPU): `all`, the first N adapters, or a
    /// comma-separated list of adapter indices, PCI bus ids or names (`--adapter` is then
    /// not used).
    #[arg(long)]
    pub gpus: Option<String>,
}

impl CompareArgs {
    /// The comparison these arguments name.
    pub fn spec(self) -> CompareSpec {
        CompareSpec {
            options: self.common.run_options(),
            runs: self.runs,
            reference: self.reference,
            resume: self.resume,
            baseline: self.baseline,
            comparison: self.flags.comparison(self.time, self.out, self.gpus, self.force),
        }
    }
}

/// Runs the comparison ([`lightgraph::compare::render::compare`]) and prints its summary.
pub fn compare(args: CompareArgs) -> Result<()> {
    let out = args.out.clone();
    let summary = lightgraph::compare::render::compare(args.spec()).map_err(with_resume_command)?;
    println!(
        "{summary}\nwrote {}/curves.csv, rmse_vs_time.png, summary.md, each run's EXR and PNG, and {} (opens offline \
         in a browser)",
        out.display(),
        html_path(&out).display()
    );
    Ok(())
}
