//! `lightgraph reference`: a long render accumulated in f64 on the host, with its variance,
//! written as a reference EXR and resumable ([`lightgraph::reference::render`]).

use super::args::*;
use super::film::{FilmArgs, FilmDefaults};
use anyhow::Result;
use clap::Args;
use lightgraph::reference::{REFERENCE_CHECKPOINT, REFERENCE_SEED, ReferenceSpec, render};

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    #[command(flatten)]
    pub tev: TevArg,
    #[command(flatten)]
    pub film: FilmArgs,
}

/// What a reference's film defaults to: seed 1000003, out/reference.exr, a checkpoint every
/// 5 minutes.
pub const REFERENCE: FilmDefaults = FilmDefaults {
    seed: REFERENCE_SEED,
    out: "out/reference.exr",
    checkpoint: Some(REFERENCE_CHECKPOINT),
};

impl ReferenceArgs {
    /// The reference these arguments name; the film `--resume` names is read and gives the
    /// settings not given, and `--frames` (the film's total) becomes the frames to render.
    pub fn spec(mut self) -> Result<ReferenceSpec> {
        let resumed = self.film.resume(&mut self.common, &mut self.graph, &REFERENCE)?;
        let film = self.film;
        Ok(ReferenceSpec {
            run: self
                .common
                .spec(self.graph.name(), film.layout.as_deref(), film.seed(&REFERENCE)),
            time: film.time,
            frames: film.time.is_none().then_some(film.frames_left),
            out: film.out(&REFERENCE),
            resume: film.resume.clone().zip(resumed),
            force: film.force,
            checkpoint: film.checkpoint(&REFERENCE).unwrap_or(REFERENCE_CHECKPOINT),
            exposure: film.exposure,
            first_frame: film.first_frame,
            gpus: film.gpus,
            tev: self.tev.tev,
        })
    }
}

/// Renders the reference the arguments name ([`lightgraph::reference::render`]).
pub fn reference(args: ReferenceArgs) -> Result<()> {
    render(args.spec()?)
}
