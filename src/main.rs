//! The `lightgraph` command line: render, reference, merge, compare, stress, explain, bench,
//! operators, list.

mod cli;

use clap::{Parser, Subcommand};
use cli::bench::BenchArgs;
use cli::compare::CompareArgs;
use cli::explain::ExplainArgs;
use cli::merge::MergeArgs;
use cli::operators::OperatorsArgs;
use cli::reference::ReferenceArgs;
use cli::render::RenderArgs;
use cli::stress::StressArgs;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "lightgraph",
    version,
    about = "GPU progressive light transport: algorithms as frame graphs of compute passes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene progressively and write an EXR and a PNG preview.
    Render(RenderArgs),
    /// Render a long reference accumulated in f64, with its variance; resumable.
    Reference(ReferenceArgs),
    /// Add films of the same settings over disjoint frame ranges (shards of one run) into one.
    Merge(MergeArgs),
    /// Render several estimators and layouts for the same time and plot their error against
    /// a reference over time.
    Compare(CompareArgs),
    /// Run the numerical stress suite: extreme scenes with every estimator, each checked
    /// against its invariant.
    Stress(StressArgs),
    /// Print the kernels, schedule and resources of a graph's layouts.
    Explain(ExplainArgs),
    /// Measure layouts over a sweep of paths per frame: Markdown table, CSV and PNG plot.
    Bench(BenchArgs),
    /// Check the engine's collective operators (scan, counting sort) against the CPU and
    /// time them on the GPU.
    Operators(OperatorsArgs),
    /// List built-in graphs with their layouts, built-in scenes and GPU adapters.
    List,
}

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread starts; silences the Vulkan loader's warning.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let assets = match &cli.command {
        Command::Render(a) => a.common.assets.clone(),
        Command::Reference(a) => a.common.assets.clone(),
        Command::Compare(a) => a.common.assets.clone(),
        Command::Explain(a) => a.common.assets.clone(),
        Command::Bench(a) => a.common.assets.clone(),
        Command::List | Command::Stress(_) | Command::Operators(_) | Command::Merge(_) => None,
    };
    if let Some(dir) = assets {
        // SAFETY: set before any thread starts; scene loading reads it.
        unsafe { std::env::set_var("LIGHTGRAPH_ASSETS", dir) };
    }
    let result = match cli.command {
        Command::Render(a) => cli::render::render(a),
        Command::Reference(a) => cli::reference::reference(a),
        Command::Merge(a) => cli::merge::merge(a),
        Command::Compare(a) => cli::compare::compare(a),
        Command::Explain(a) => cli::explain::explain(a),
        Command::Bench(a) => cli::bench::bench(a),
        Command::List => cli::list::list(),
        Command::Stress(a) => cli::stress::stress(a),
        Command::Operators(a) => cli::operators::operators(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
