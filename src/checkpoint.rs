//! A film that grows on the host while the driver renders into it, and its checkpoints:
//! [`Filmed`] is one GPU's session whose sums go into a film (the driver's executor of
//! `render` and `reference` on one GPU), and [`Checkpoint`] the one observer that writes the
//! film with its PNG preview every so often, so that a run that is killed keeps its frames up
//! to the last checkpoint. `render` and `reference` write their checkpoints through it, on one
//! GPU (as an observer of [`Filmed`]) and on several ([`Checkpoint::write_if_due`]).

use crate::drive::{Executor, Observer, Stopwatch};
use crate::film::Film;
use crate::output::write_png;
use crate::run::Session;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Writes `film` to `out` as an EXR that `kind` wrote (render, reference) and its PNG preview
/// beside it at `exposure` stops; returns the PNG's path.
pub fn write_with_preview(film: &Film, out: &Path, kind: &str, exposure: f32) -> Result<PathBuf> {
    film.write(out, kind)?;
    let png = out.with_extension("png");
    write_png(&png, &film.image(), exposure)?;
    Ok(png)
}

/// One GPU's session rendering into a film on the host: the driver's executor (it renders
/// as the session does) with the film the session's sums are moved into.
pub struct Filmed<'a, 'g> {
    /// The session that renders.
    pub session: &'a mut Session<'g>,
    /// The film (in f64) the session's sums go into when they are absorbed.
    pub film: &'a mut Film,
    /// The frames the film held when the session began rendering into it.
    film_frames_at_start: u64,
    absorbed_at: Instant,
}

impl<'a, 'g> Filmed<'a, 'g> {
    /// The session rendering into `film`; the film's seconds count from now.
    pub fn new(session: &'a mut Session<'g>, film: &'a mut Film) -> Self {
        Filmed {
            film_frames_at_start: film.frames,
            session,
            film,
            absorbed_at: Instant::now(),
        }
    }

    /// The frames of the film and the session together: those the film held at the start
    /// and the session's, however many of them were absorbed into the film already.
    pub fn frames_in_all(&self) -> u64 {
        self.film_frames_at_start + self.session.frames as u64
    }

    /// Moves the GPU's sums into the film and adds the seconds since the last time.
    pub fn absorb(&mut self) -> Result<()> {
        self.film.absorb(&self.session.take_accumulation()?)?;
        self.film.seconds += self.absorbed_at.elapsed().as_secs_f64();
        self.absorbed_at = Instant::now();
        Ok(())
    }

    /// The mean of every frame so far: the film's and the GPU's not yet absorbed.
    pub fn mean(&self) -> Result<Vec<[f32; 3]>> {
        if self.film.frames == 0 {
            return Ok(self.session.image()?.mean);
        }
        let mut all = self.film.clone();
        all.absorb(&self.session.accumulation()?)?;
        Ok(all.mean())
    }
}

impl Executor for Filmed<'_, '_> {
    fn frames(&self) -> u64 {
        self.session.frames()
    }

    fn advance(&mut self, left: Option<Duration>, max: u64) -> Result<()> {
        self.session.advance(left, max)
    }

    fn settle(&mut self) -> Result<()> {
        Executor::settle(&mut *self.session)
    }
}

/// Writes a film and its PNG preview every `--checkpoint` while a drive renders into it (the
/// first one a period after it was made, or with the first frames: [`Checkpoint::at_first`]);
/// with no period, never.
pub struct Checkpoint<'a> {
    every: Option<Duration>,
    out: &'a Path,
    kind: &'static str,
    exposure: f32,
    /// When the last checkpoint was written (None: none yet, and the first is due at once).
    saved_at: Option<Instant>,
}

impl<'a> Checkpoint<'a> {
    /// Checkpoints of the film at `out` that `kind` writes, every `every`, with the preview at
    /// `exposure` stops.
    pub fn new(every: Option<Duration>, out: &'a Path, kind: &'static str, exposure: f32) -> Self {
        Checkpoint {
            every,
            out,
            kind,
            exposure,
            saved_at: Some(Instant::now()),
        }
    }

    /// These checkpoints with the first one due at once: on several GPUs, whose first batches
    /// reach the host together and whose claims grow with their speed (a short render may
    /// arrive in two batches), the first frames are kept as soon as they arrive.
    pub fn at_first(self) -> Self {
        Checkpoint { saved_at: None, ..self }
    }

    /// Whether the period has passed since the last checkpoint.
    pub fn due(&self) -> bool {
        self.every
            .is_some_and(|every| self.saved_at.is_none_or(|t| t.elapsed() >= every))
    }

    /// Writes `film` (up to date: on several GPUs, the host's) if a checkpoint is due.
    pub fn write_if_due(&mut self, film: &Film) -> Result<()> {
        if self.due() {
            write_with_preview(film, self.out, self.kind, self.exposure)?;
            self.saved_at = Some(Instant::now());
        }
        Ok(())
    }
}

/// On one GPU: when a checkpoint is due, the GPU's sums go into the film, which is written.
impl Observer<Filmed<'_, '_>> for Checkpoint<'_> {
    fn batch(&mut self, exec: &mut Filmed<'_, '_>, _: &mut Stopwatch) -> Result<()> {
        if self.due() {
            exec.absorb()?;
            self.write_if_due(exec.film)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn a_checkpoint_writes_the_film_and_its_preview_once_its_period_has_passed() {
        let dir = std::env::temp_dir().join(format!("lightgraph-checkpoint-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("film.exr");
        let film = Film::new((2, 1), BTreeMap::new());
        for every in [None, Some(Duration::from_secs(3600))] {
            Checkpoint::new(every, &out, "render", 0.0).write_if_due(&film).unwrap();
            assert!(!out.exists(), "written before its period ({every:?})");
        }
        let hour = Some(Duration::from_secs(3600));
        assert!(
            Checkpoint::new(hour, &out, "render", 0.0).at_first().due(),
            "at_first: due with the first frames"
        );
        assert!(
            !Checkpoint::new(None, &out, "render", 0.0).at_first().due(),
            "no period, no checkpoint"
        );
        let mut checkpoint = Checkpoint::new(Some(Duration::ZERO), &out, "render", 0.0);
        assert!(checkpoint.due());
        checkpoint.write_if_due(&film).unwrap();
        assert!(out.is_file() && out.with_extension("png").is_file());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
