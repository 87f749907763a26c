//! What `render` and `reference` share about their film, declared once: the options of a run
//! into one film ([`FilmArgs`]: its budget, seed, file, resuming, checkpoints, preview and
//! GPUs) and resuming one (`--resume`: the settings it was made with, the frames left).

use super::args::{Common, GraphArg};
use super::checks::{count, duration};
use anyhow::Result;
use clap::Args;
use lightgraph::drive::Budget;
use lightgraph::film::{CLI_LENGTH_OPTIONS, DEFAULT_FRAMES, Film};
use std::path::PathBuf;
use std::time::Duration;

/// What differs between the commands that render a film: their defaults.
pub struct FilmDefaults {
    /// The seed when neither --seed nor a resumed film gives one.
    pub seed: u32,
    /// The film's path when neither --out nor --resume gives one.
    pub out: &'static str,
    /// The checkpoints' period when --checkpoint is not given (None: no checkpoints).
    pub checkpoint: Option<Duration>,
}

/// The options of a run into one film (`render`, `reference`), each declared, documented and
/// checked here once; [`FilmArgs::resume`] reads a resumed film before any work.
#[derive(Args)]
pub struct FilmArgs {
    /// Kernel layout (default: the graph's); every layout of a graph gives the same image.
    /// `render --layout auto` measures every legal layout first and renders with the fastest.
    #[arg(long)]
    pub layout: Option<String>,
    /// Render for this long (e.g. 10s, 2m) instead of a number of frames; with --resume, the
    /// time this invocation adds to the film's.
    #[arg(long, value_parser = duration, allow_hyphen_values = true)]
    pub time: Option<Duration>,
    /// The frames the film holds at the end [default: 64]: with --resume, its frames
    /// included (a film of 64 frames resumed with --frames 256 gets 192 more). Give --frames
    /// or --time, not both.
    #[arg(long, conflicts_with = "time", value_parser = count::<u32>, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// The frames this invocation renders: --frames, less those a resumed film holds (set by
    /// [`FilmArgs::resume`]).
    #[arg(skip)]
    pub frames_left: u32,
    /// Seed of the random streams [default: the resumed film's, else 1 for `render` and
    /// 1000003 for `reference`, whose random numbers must differ from the runs compared with
    /// it].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Output EXR (the film; it must end in .exr) [default: the resumed film, else
    /// out/render.exr or out/reference.exr]; a PNG preview is written beside it. An existing
    /// file is refused unless --force or --resume names it.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing --out.
    #[arg(long)]
    pub force: bool,
    /// Continue this film (from `render` or `reference`, e.g. one a signal stopped): scene,
    /// graph, resolution, samples per frame, seed and constants default to its own and must
    /// match when given; the frames follow its last one. --frames counts the film's frames in
    /// all (its own included; one that holds as many already is refused before any work),
    /// --time this invocation's time.
    #[arg(long, value_name = "FILM.exr")]
    pub resume: Option<PathBuf>,
    /// Write the film (and the PNG) every this often while rendering (e.g. 10m), so a run
    /// that is killed keeps its frames up to the last checkpoint [default: 5m for
    /// `reference`, none for `render`].
    #[arg(long, value_parser = duration, allow_hyphen_values = true)]
    pub checkpoint: Option<Duration>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Frame index of the first frame [default: 0, or where the resumed film ends; with
    /// --resume, never inside its frames]: the frames rendered are FIRST, FIRST + 1, ... of
    /// the seed's random streams, a shard of a longer run (`lightgraph merge` adds the
    /// shards' films).
    #[arg(long)]
    pub first_frame: Option<u32>,
    /// Render on several GPUs at once: `all`, the first N adapters, or a comma-separated list
    /// of adapter indices, PCI bus ids or names (see `lightgraph list`; one may repeat). Each
    /// GPU claims batches of frames sized to its own speed; the host adds them into one film
    /// (`--adapter` is then not used).
    #[arg(long)]
    pub gpus: Option<String>,
}

impl FilmArgs {
    /// The frames the film holds at the end: --frames, else 64.
    pub fn frames(&self) -> u32 {
        self.frames.unwrap_or(DEFAULT_FRAMES)
    }

    /// The film's path: --out, else the resumed film, else the command's default.
    pub fn out(&self, defaults: &FilmDefaults) -> PathBuf {
        self.out
            .clone()
            .or_else(|| self.resume.clone())
            .unwrap_or_else(|| PathBuf::from(defaults.out))
    }

    /// The seed: --seed (or the resumed film's), else the command's default.
    pub fn seed(&self, defaults: &FilmDefaults) -> u32 {
        self.seed.unwrap_or(defaults.seed)
    }

    /// The checkpoints' period: --checkpoint, else the command's default.
    pub fn checkpoint(&self, defaults: &FilmDefaults) -> Option<Duration> {
        self.checkpoint.or(defaults.checkpoint)
    }

    /// The index of the first frame this invocation renders (after [`FilmArgs::resume`]).
    pub fn first_frame(&self) -> u32 {
        self.first_frame.unwrap_or(0)
    }

    /// This invocation's budget: --time, else the frames left ([`FilmArgs::frames_left`]).
    pub fn budget(&self) -> Budget {
        match self.time {
            Some(t) => Budget::Time(t),
            None => Budget::Frames(self.frames_left as u64),
        }
    }

    /// Reads the film --resume names, before any work: the settings the command line leaves
    /// out (in `common`, `graph` and the seed) become the film's, the frames left become
    /// --frames less those it holds (refused when it holds as many already) and the first
    /// frame is where it ends (or --first-frame, after its frames). Without --resume, the
    /// frames left are --frames.
    pub fn resume(
        &mut self,
        common: &mut Common,
        graph: &mut GraphArg,
        defaults: &FilmDefaults,
    ) -> Result<Option<Film>> {
        self.frames_left = self.frames();
        let Some(path) = self.resume.clone() else {
            return Ok(None);
        };
        let film = Film::read(&path)?;
        let mut options = common.run_options();
        options.from_film(&mut graph.graph, &mut self.seed, defaults.seed, &film);
        common.take(options);
        if self.time.is_none() {
            self.frames_left = film.frames_left(self.frames(), &path, &CLI_LENGTH_OPTIONS)?;
        }
        self.first_frame = Some(film.next_first_frame(self.first_frame)?);
        Ok(Some(film))
    }
}
