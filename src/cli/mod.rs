//! The commands of the `lightgraph` binary, one module each, the options they share, and the
//! command line that chooses one (also run from the Python module).

pub mod args;
pub mod assets;
pub mod bench;
pub use crate::run::checks;
pub mod compare;
pub mod docs;
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

    /// Whether the command stops at a signal keeping its work (`render`, `reference`,
    /// `compare`, `study`: [`lightgraph::interrupt`]); the others end at once, as a signal's
    /// default does.
    pub fn keeps_work_on_signal(&self) -> bool {
        matches!(
            self.command,
            Command::Render(_) | Command::Reference(_) | Command::Compare(_) | Command::Study(_)
        )
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

#[cfg(test)]
mod tests {
    use super::{Cli, Command};
    use crate::compare::render::{COMPARE_OUT, COMPARE_TIME, PER_DECADE};
    use crate::run::DEFAULT_SEED;
    use crate::study::render::{LAYOUT_TIME, REFERENCE_GRAPH, REFERENCE_TIME, STUDY_OUT, STUDY_TIME};
    use std::collections::BTreeMap;
    use std::path::{Path, PathBuf};
    use std::time::Duration;

    /// The default of each keyword of `def NAME(` in Python's stub (python/lightgraph.pyi), as
    /// written there.
    fn stub_defaults(name: &str) -> BTreeMap<String, String> {
        let stub = include_str!("../../python/lightgraph.pyi");
        let def = &stub[stub.find(&format!("\ndef {name}(")).expect("the function in the stub")..];
        let params = &def[..def.find(") ->").expect("its end")];
        params
            .lines()
            .filter_map(|l| {
                let (name, default) = l.trim().trim_end_matches(',').split_once(" = ")?;
                Some((name.split(':').next()?.trim().to_string(), default.to_string()))
            })
            .collect()
    }

    /// A number of seconds as the stub writes it (`20.0`).
    fn seconds(time: Duration) -> String {
        format!("{:?}", time.as_secs_f64())
    }

    /// The library's constants are the defaults of `compare` and `study` on the command line
    /// (which takes them from there) and in Python's stub (which repeats them, as a stub must).
    #[test]
    fn compare_and_study_defaults_come_from_the_library() {
        let Command::Compare(compare) =
            Cli::parse_from_args(["lightgraph", "compare", "--runs", "pt", "--reference", "r.exr"])
                .unwrap()
                .command
        else {
            panic!("compare")
        };
        let compare = compare.spec().comparison;
        assert_eq!(compare.budget.time, COMPARE_TIME);
        assert_eq!((compare.per_decade, compare.seed), (PER_DECADE, DEFAULT_SEED));
        assert_eq!(compare.out, Path::new(COMPARE_OUT));
        let Command::Study(study) = Cli::parse_from_args(["lightgraph", "study", "--scenes", "a"])
            .unwrap()
            .command
        else {
            panic!("study")
        };
        let study = study.spec();
        assert_eq!((study.layout_time, study.reference_time), (LAYOUT_TIME, REFERENCE_TIME));
        assert_eq!(study.reference_graph, REFERENCE_GRAPH);
        let c = &study.comparison;
        assert_eq!(
            (c.budget.time, c.per_decade, c.seed),
            (STUDY_TIME, PER_DECADE, DEFAULT_SEED)
        );
        assert_eq!(c.out, Path::new(STUDY_OUT));

        let quoted = |s: &str| format!("\"{s}\"");
        let compare = stub_defaults("compare");
        assert_eq!(compare["time"], seconds(COMPARE_TIME));
        assert_eq!(compare["seed"], DEFAULT_SEED.to_string());
        assert_eq!(compare["out"], quoted(COMPARE_OUT));
        assert_eq!(compare["per_decade"], PER_DECADE.to_string());
        let study = stub_defaults("study");
        assert_eq!(study["time"], seconds(STUDY_TIME));
        assert_eq!(study["reference_time"], seconds(REFERENCE_TIME));
        assert_eq!(study["reference_graph"], quoted(REFERENCE_GRAPH));
        assert_eq!(study["seed"], DEFAULT_SEED.to_string());
        assert_eq!(study["out"], quoted(STUDY_OUT));
    }

    /// The command `words` parses to.
    fn command(words: &[&str]) -> Command {
        Cli::parse_from_args([&["lightgraph"], words].concat()).unwrap().command
    }

    /// `--setup-on-clock`, declared once for `compare` and `study`, reaches both budgets.
    #[test]
    fn setup_on_clock_reaches_compare_and_study() {
        for on in [false, true] {
            let flag: &[&str] = if on { &["--setup-on-clock"] } else { &[] };
            let Command::Compare(compare) =
                command(&[&["compare", "--runs", "pt", "--reference", "r.exr"], flag].concat())
            else {
                panic!("compare")
            };
            assert_eq!(compare.spec().comparison.budget.setup_on_clock, on);
            let Command::Study(study) = command(&[&["study", "--scenes", "a"], flag].concat()) else {
                panic!("study")
            };
            assert_eq!(study.spec().comparison.budget.setup_on_clock, on);
        }
    }

    /// `render` and `reference` take the same film options, with their own defaults: a
    /// reference's seed, file and checkpoints, and 64 frames for both.
    #[test]
    fn render_and_reference_share_the_film_options_with_their_defaults() {
        let Command::Render(render) = command(&["render"]) else {
            panic!("render")
        };
        let Command::Reference(reference) = command(&["reference"]) else {
            panic!("reference")
        };
        assert_eq!(render.out(), Path::new("out/render.exr"));
        assert_eq!((render.spec().seed, render.film.frames()), (1, 64));
        assert_eq!(render.film.checkpoint(&super::render::RENDER), None);
        let spec = reference.spec().unwrap();
        assert_eq!(spec.out, Path::new("out/reference.exr"));
        assert_eq!(
            (spec.run.seed, spec.frames),
            (crate::reference::REFERENCE_SEED, Some(64))
        );
        assert_eq!(spec.checkpoint, crate::reference::REFERENCE_CHECKPOINT);
        let given = ["--frames", "5", "--seed", "9", "--out", "x.exr", "--checkpoint", "1m"];
        let Command::Reference(reference) = command(&[&["reference"], &given[..]].concat()) else {
            panic!("reference")
        };
        let spec = reference.spec().unwrap();
        assert_eq!(
            (spec.out.as_path(), spec.run.seed, spec.frames),
            (Path::new("x.exr"), 9, Some(5))
        );
        assert_eq!(spec.checkpoint, Duration::from_secs(60));
    }

    /// A default time shows on the command line as it is typed there and reads back the same.
    #[test]
    fn default_times_read_back() {
        for (time, text) in [
            (LAYOUT_TIME, "500ms"),
            (STUDY_TIME, "20s"),
            (REFERENCE_TIME, "2m"),
            (COMPARE_TIME, "10s"),
        ] {
            assert_eq!(super::args::duration_text(time), text);
            assert_eq!(super::checks::duration(text), Ok(time));
        }
    }

    /// The command modules: those [`super::Cli::run`] dispatches to (`name::function(a)` in
    /// its match), read from this file.
    fn command_modules(mod_rs: &str) -> Vec<String> {
        let run = &mod_rs[mod_rs.find("pub fn run(self)").expect("Cli::run")..];
        run.lines()
            .filter_map(|l| {
                l.split_once("=> ")?
                    .1
                    .split_once("::")
                    .map(|(m, _)| m.trim().to_string())
            })
            .collect()
    }

    /// The files under `dir`, recursively.
    fn files(dir: &Path) -> Vec<PathBuf> {
        let mut out = Vec::new();
        for entry in std::fs::read_dir(dir).expect("src/cli") {
            let path = entry.expect("entry").path();
            match path.is_dir() {
                true => out.extend(files(&path)),
                false => out.push(path),
            }
        }
        out
    }

    /// The module path under `cli` of the file `rel` (relative to src/cli): `render/gpus.rs`
    /// is [render, gpus], `render/mod.rs` [render], `mod.rs` [].
    fn module_of(rel: &Path) -> Vec<String> {
        let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        let file = parts.pop().expect("a file name");
        if file != "mod.rs" {
            parts.push(file.trim_end_matches(".rs").to_string());
        }
        parts
    }

    /// The module directly under `cli` that a `use` line of module `module` names, if it
    /// names one: `use super::...` (relative to the module), `use crate::cli::...` or
    /// `use lightgraph::cli::...`.
    fn used_module(module: &[String], line: &str) -> Option<String> {
        let path = line.trim().trim_start_matches("pub ").strip_prefix("use ")?;
        let mut at: Vec<String> = match path {
            p if p.starts_with("crate::cli::") || p.starts_with("lightgraph::cli::") => Vec::new(),
            p if p.starts_with("super::") => module.to_vec(),
            _ => return None,
        };
        let rest = path
            .trim_start_matches("crate::cli::")
            .trim_start_matches("lightgraph::cli::");
        let mut rest = rest;
        while let Some(r) = rest.strip_prefix("super::") {
            at.pop();
            rest = r;
        }
        let first = rest
            .split([':', ';', ',', '{', ' '])
            .next()
            .unwrap_or_default()
            .to_string();
        Some(at.first().cloned().unwrap_or(first))
    }

    /// No file under src/cli/ imports another command's module. The command modules are those
    /// `Cli::run` dispatches to; a file belongs to the command whose module it is or is under
    /// (`render/gpus.rs` to `render`), and `mod.rs` to none. Each `use` (or `pub use`) line
    /// starting `use super::`, `use crate::cli::` or `use lightgraph::cli::` is resolved to
    /// the module directly under `cli` it names; naming a command module other than the
    /// file's own is an error. The shared helpers (`args`, `checks`, which re-exports
    /// `lightgraph::run::checks`, `film`) are not commands and may be imported by any; only
    /// `mod.rs`, which declares and dispatches to the commands, names them all.
    #[test]
    fn no_command_module_imports_another() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/cli");
        let commands = command_modules(&std::fs::read_to_string(dir.join("mod.rs")).expect("mod.rs"));
        assert!(commands.contains(&"render".to_string()), "{commands:?}");
        let mut wrong = Vec::new();
        for file in files(&dir) {
            let rel = file.strip_prefix(&dir).expect("under src/cli");
            let module = module_of(rel);
            let Some(own) = module.first() else { continue };
            let text = std::fs::read_to_string(&file).expect("a source file");
            for line in text.lines() {
                match used_module(&module, line) {
                    Some(used) if &used != own && commands.contains(&used) => {
                        wrong.push(format!("{}: {}", rel.display(), line.trim()));
                    }
                    _ => {}
                }
            }
        }
        assert!(
            wrong.is_empty(),
            "command modules importing another's:\n{}",
            wrong.join("\n")
        );
    }
}
