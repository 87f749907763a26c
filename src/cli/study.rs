//! `lightgraph study`: the best layout of each estimator on a list of scenes, each run given
//! the same wall-clock budget against a reference per scene (given, resumed or rendered by
//! the study), a comparison per scene (as `lightgraph compare` writes it) and one summary
//! ([`lightgraph::study::render`]).

use super::args::*;
use anyhow::Result;
use clap::Args;
use lightgraph::study::DEFAULT_ESTIMATORS;
use lightgraph::study::render::{LAYOUT_TIME, REFERENCE_GRAPH, REFERENCE_TIME, STUDY_OUT, STUDY_TIME, StudySpec};
use std::path::PathBuf;
use std::time::Duration;

/// The arguments of `lightgraph study`.
#[derive(Args)]
pub struct StudyArgs {
    #[command(flatten)]
    pub common: Common,
    /// Scenes, comma-separated: built-in names or scene files, as `--scene` takes them (which
    /// `study` does not take).
    #[arg(long, value_delimiter = ',', required = true)]
    pub scenes: Vec<String>,
    /// Estimators, comma-separated: a graph (its layouts are measured on each scene and the
    /// one with the most samples per second runs) or `graph:Layout`, each optionally with
    /// `@NAME=VALUE` constants of its own (as `compare --runs`).
    #[arg(long, default_value = DEFAULT_ESTIMATORS)]
    pub estimators: String,
    /// Wall-clock budget of each estimator on each scene (rendering: its set-up is off the clock unless `--setup-on-clock`).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = duration_text(STUDY_TIME))]
    pub time: Duration,
    /// Continue the study in --out (after a signal stopped it): scenes and runs whose results
    /// are there are not rendered again, layouts not measured again; its settings must be
    /// these.
    #[arg(long)]
    pub resume: bool,
    /// Time each layout renders when the study measures a graph's layouts (after a warm-up
    /// frame, so pipeline creation is not measured).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = duration_text(LAYOUT_TIME))]
    pub layout_time: Duration,
    /// Folder of the references, one per scene (`<folder>.exr`, the folder the scene's
    /// outputs get): used when there with enough samples, resumed when there with fewer,
    /// rendered when not there [default: <out>/references].
    #[arg(long)]
    pub references: Option<PathBuf>,
    /// The graph that renders references.
    #[arg(long, default_value = REFERENCE_GRAPH)]
    pub reference_graph: String,
    /// The layout that renders references (default: the reference graph's).
    #[arg(long)]
    pub reference_layout: Option<String>,
    /// Render seconds each reference must hold; one with fewer is resumed for the rest.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = duration_text(REFERENCE_TIME))]
    pub reference_time: Duration,
    /// Frames each reference must hold instead (for reproducible references and tests).
    #[arg(long, conflicts_with = "reference_time", value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub reference_frames: Option<u32>,
    /// Samples per pixel in each frame of references the study renders [default: --spp].
    #[arg(long, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub reference_spp: Option<u32>,
    #[command(flatten)]
    pub flags: CompareFlags,
    /// Output folder: summary.md, summary.csv, layouts.csv, report.html, and per scene a folder
    /// with curves.csv, rmse_vs_time.png, summary.md, report.html and each run's EXR and PNG.
    #[arg(long, default_value = STUDY_OUT)]
    pub out: PathBuf,
    /// Write into a --out that holds an earlier study, replacing its files.
    #[arg(long)]
    pub force: bool,
    /// Run on several GPUs of one model at once, as `compare --gpus` (references as
    /// `reference --gpus`; layouts are measured on the first).
    #[arg(long)]
    pub gpus: Option<String>,
}

impl StudyArgs {
    /// The study these arguments name.
    pub fn spec(self) -> StudySpec {
        StudySpec {
            options: self.common.run_options(),
            scenes: self.scenes,
            estimators: self.estimators,
            resume: self.resume,
            layout_time: self.layout_time,
            references: self.references,
            reference_graph: self.reference_graph,
            reference_layout: self.reference_layout,
            reference_time: self.reference_time,
            reference_frames: self.reference_frames,
            reference_spp: self.reference_spp,
            comparison: self.flags.comparison(self.time, self.out, self.gpus, self.force),
        }
    }
}

/// Runs the study ([`lightgraph::study::render::study`]) and prints its summary.
pub fn study(args: StudyArgs) -> Result<()> {
    let out = args.out.clone();
    let summary = lightgraph::study::render::study(args.spec()).map_err(with_resume_command)?;
    println!(
        "{summary}\nwrote {0}/summary.md, summary.csv, layouts.csv, {1} (opens offline in a browser) and a \
         comparison per scene in {0}/<scene>/",
        out.display(),
        lightgraph::study::html::html_path(&out).display()
    );
    Ok(())
}
