//! `lightgraph reference`: a long render accumulated in f64 on the host, with its variance,
//! written as a reference EXR and resumable ([`lightgraph::reference::render`]).

use super::args::*;
use super::film::settings_from_film;
use anyhow::Result;
use clap::Args;
use lightgraph::film::Film;
use lightgraph::reference::{REFERENCE_SEED, ReferenceSpec, out_path, render};
use std::path::PathBuf;
use std::time::Duration;

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    #[command(flatten)]
    pub tev: TevArg,
    /// Kernel layout (default: the graph's); every layout of a graph gives the same image.
    #[arg(long)]
    pub layout: Option<String>,
    /// Render for this long (added to what a resumed reference has).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, required_unless_present = "frames")]
    pub time: Option<Duration>,
    /// Render this many frames instead (for reproducible references and tests).
    #[arg(long, conflicts_with = "time", value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Seed of the random streams [default: 1000003, or the resumed reference's].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Add samples to this reference; scene, graph, resolution, samples per frame, seed and
    /// constants default to its own, and must match when given.
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Output EXR [default: the resumed file, else out/reference.exr]; a PNG preview is
    /// written beside it.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing --out (without it, an existing file is refused unless --resume
    /// names it).
    #[arg(long)]
    pub force: bool,
    /// Write the reference every this often while rendering, so a long run that is stopped
    /// keeps its samples.
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "5m")]
    pub checkpoint: Duration,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Frame index of the first frame [default: 0, or where the resumed reference ends]: the
    /// shard of one run that this process renders (`merge` adds the shards up).
    #[arg(long)]
    pub first_frame: Option<u32>,
    /// Render on several GPUs at once, as `render --gpus`: `all`, the first N adapters, or a
    /// comma-separated list of adapter indices, PCI bus ids or names (`--adapter` is then
    /// not used).
    #[arg(long)]
    pub gpus: Option<String>,
}

impl ReferenceArgs {
    /// The reference these arguments name; the film `--resume` names is read and gives the
    /// settings not given.
    pub fn spec(mut self) -> Result<ReferenceSpec> {
        let resume = match self.resume.take() {
            Some(path) => Some((Film::read(&path)?, path)),
            None => None,
        };
        if let Some((film, _)) = &resume {
            settings_from_film(&mut self.common, &mut self.graph, &mut self.seed, REFERENCE_SEED, film);
        }
        let seed = self.seed.unwrap_or(REFERENCE_SEED);
        let resume_path = resume.as_ref().map(|(_, p)| p.as_path());
        Ok(ReferenceSpec {
            run: self.common.spec(self.graph.name(), self.layout.as_deref(), seed),
            time: self.time,
            frames: self.frames,
            out: out_path(self.out.as_deref(), resume_path),
            resume: resume.map(|(film, path)| (path, film)),
            force: self.force,
            checkpoint: self.checkpoint,
            exposure: self.exposure,
            first_frame: self.first_frame,
            gpus: self.gpus,
            tev: self.tev.tev,
        })
    }
}

/// Renders the reference the arguments name ([`lightgraph::reference::render`]).
pub fn reference(args: ReferenceArgs) -> Result<()> {
    render(args.spec()?)
}
