//! The `lightgraph` command line: render, reference, merge, compare, study, stress, explain, export, bench,
//! operators, list, assets (the commands live in `lightgraph::cli`).

use clap::Parser;
use lightgraph::cli::Cli;
use std::process::ExitCode;

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before any thread starts; silences the Vulkan loader's warning.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    if let Some(dir) = cli.assets() {
        // SAFETY: set before any thread starts; scene loading reads it.
        unsafe { std::env::set_var("LIGHTGRAPH_ASSETS", dir) };
    }
    if cli.keeps_work_on_signal()
        && let Err(e) = lightgraph::interrupt::install()
    {
        eprintln!("warning: SIGINT and SIGTERM will end runs without keeping their work: {e}");
    }
    match cli.run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(lightgraph::interrupt::exit_code(&e))
        }
    }
}
