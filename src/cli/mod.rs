//! The commands of the `lightgraph` binary, one module each, the options they share, and the
//! command line that chooses one (also run from the Python module).

pub mod args;
pub mod assets;
pub mod bench;
pub use crate::run::checks;
pub mod compare;
pub mod explain;
pub mod export;
pub mod film;
pub mod list;
pub mod merge;
pub mod operators;
pub mod reference;
pub mod render;
pub mod stress;
pub mod study;
pub mod verify;

use assets::AssetsArgs;
use bench::BenchArgs;
use clap::{Parser, Subcommand};
use compare::CompareArgs;
use explain::ExplainArgs;
use export::ExportArgs;
use merge::MergeArgs;
use operators::OperatorsArgs;
use reference::ReferenceArgs;
use render::RenderArgs;
use stress::StressArgs;
use study::StudyArgs;
use verify::VerifyArgs;

/// The command line: one of the commands with its arguments.
#[derive(Parser)]
#[command(
    name = "lightgraph",
    version,
    about = "GPU progressive light transport: algorithms as frame graphs of compute passes"
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
    /// Render a scene progressively and write an EXR and a PNG preview.
    Render(RenderArgs),
    /// Render a long reference accumulated in f64, with its variance; resumable.
    Reference(ReferenceArgs),
    /// Add films of the same settings over disjoint frame ranges (shards of one run) into one.
    Merge(MergeArgs),
    /// Render several estimators and layouts for the same time and plot their error against
    /// a reference over time.
    Compare(CompareArgs),
    /// Run the best layout of each estimator on a list of scenes for equal wall-clock budgets
    /// against a reference per scene: error against time per scene and one summary of the
    /// time each takes to the best final error, and the winner.
    Study(StudyArgs),
    /// Check every estimator against every other on a list of scenes: which pairs agree,
    /// which differ (and where), predicted from what each graph declares it cannot sample.
    Verify(VerifyArgs),
    /// Run the numerical stress suite: extreme scenes with every estimator, each checked
    /// against its invariant.
    Stress(StressArgs),
    /// Print the kernels, schedule and resources of a graph's layouts.
    Explain(ExplainArgs),
    /// Write a scene in another renderer's format (Mitsuba 3: XML, PLY meshes, PNG textures).
    Export(ExportArgs),
    /// Measure layouts over a sweep of paths per frame: Markdown table, CSV and PNG plot.
    Bench(BenchArgs),
    /// Check the engine's collective operators (scan, counting sort) against the CPU and
    /// time them on the GPU.
    Operators(OperatorsArgs),
    /// List built-in graphs with their layouts, built-in scenes and GPU adapters.
    List,
    /// The assets scenes use (scenes/assets.toml): where each comes from, whether an asset
    /// root holds it intact, and downloading those with a public source.
    Assets(AssetsArgs),
}

impl Cli {
    /// Parses `args` (the program name first), a usage error as an error with clap's message.
    pub fn parse_from_args<I, T>(args: I) -> anyhow::Result<Cli>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        Cli::try_parse_from(args).map_err(|e| anyhow::anyhow!("{}", e.render().to_string().trim_end()))
    }

    /// The asset root `--assets` gives, if any.
    pub fn assets(&self) -> Option<std::path::PathBuf> {
        match &self.command {
            Command::Render(a) => a.common.assets.clone(),
            Command::Reference(a) => a.common.assets.clone(),
            Command::Compare(a) => a.common.assets.clone(),
            Command::Study(a) => a.common.assets.clone(),
            Command::Verify(a) => a.common.assets.clone(),
            Command::Explain(a) => a.common.assets.clone(),
            Command::Export(a) => a.assets.clone(),
            Command::Bench(a) => a.common.assets.clone(),
            Command::List | Command::Assets(_) | Command::Stress(_) | Command::Operators(_) | Command::Merge(_) => None,
        }
    }

    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        match self.command {
            Command::Render(a) => render::render(a),
            Command::Reference(a) => reference::reference(a),
            Command::Merge(a) => merge::merge(a),
            Command::Compare(a) => compare::compare(a),
            Command::Study(a) => study::study(a),
            Command::Verify(a) => verify::verify(a),
            Command::Explain(a) => explain::explain(a),
            Command::Export(a) => export::export(a),
            Command::Bench(a) => bench::bench(a),
            Command::List => list::list(),
            Command::Assets(a) => assets::assets(a),
            Command::Stress(a) => stress::stress(a),
            Command::Operators(a) => operators::operators(a),
        }
    }
}
