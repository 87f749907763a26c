//! One run of `lightgraph verify`: an estimator renders a scene in batches of equal frame
//! counts, each batch's film taken off the GPU and folded into per-block means
//! ([`BlockBatches`]) and the run's total.

use super::stats::BlockBatches;
use crate::drive::{Budget as DriveBudget, Plan, Stopwatch, drive};
use crate::film::Film;
use crate::run::{Image, Run, Session};
use anyhow::{Result, bail};
use lightgraph_engine::Gpu;
use std::time::{Duration, Instant};

/// How much a run renders: a wall-clock time (set-up off the clock) or a number of frames,
/// split into `batches` batches of equal frame counts.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    /// Seconds of rendering, or frames.
    pub amount: Amount,
    /// Batches (the standard errors' samples).
    pub batches: u32,
}

/// A run's amount of rendering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amount {
    /// Rendering time: the first batch renders for its share and fixes the frames of the rest.
    Time(Duration),
    /// Frames, rounded up to whole batches.
    Frames(u32),
}

/// What a run rendered.
pub struct RunBatches {
    /// Per-block means, batch by batch.
    pub blocks: BlockBatches,
    /// The same of the light the graph's biased technique added, where its film has that
    /// channel (FILM_BIASED).
    pub biased: Option<BlockBatches>,
    /// The whole run's image (mean and per-frame variance).
    pub image: Image,
    /// Frames rendered.
    pub frames: u32,
    /// Seconds of rendering (set-up excluded).
    pub seconds: f64,
    /// Samples the estimator rejected as NaN, Inf or negative.
    pub rejected_samples: u64,
}

/// Renders `run` for `budget`, in batches of blocks of `block` pixels; `progress` sees the
/// batches and frames done.
pub fn render_batches(
    gpu: &Gpu,
    run: &Run,
    (budget, block): (Budget, u32),
    mut progress: impl FnMut(u32, u32),
) -> Result<RunBatches> {
    if budget.batches < 2 {
        bail!("verify needs at least 2 batches a run for a standard error");
    }
    let size = (run.options.width, run.options.height);
    let mut session = run.session(gpu)?;
    let at_once = session.frames_at_once();
    let mut blocks = BlockBatches::new(size, block);
    let mut biased: Option<BlockBatches> = None;
    // The run's f64 sums over every batch, for its image.
    let mut total = Film::new(size, Default::default());
    let start = Instant::now();
    let mut per_batch = match budget.amount {
        Amount::Frames(n) => Some(n.div_ceil(budget.batches).div_ceil(at_once) * at_once),
        Amount::Time(_) => None,
    };
    for b in 0..budget.batches {
        let frames = match (per_batch, budget.amount) {
            (Some(n), _) => render_frames(&mut session, n)?,
            (None, Amount::Time(t)) => {
                let n = render_for(&mut session, t / budget.batches)?;
                per_batch = Some(n);
                n
            }
            (None, Amount::Frames(_)) => unreachable!("frame budgets fix the batch first"),
        };
        let taken = session.take_accumulation()?;
        let wide =
            |sums: &[[f32; 4]]| -> Vec<[f64; 3]> { sums.iter().map(|s| [0, 1, 2].map(|c| s[c] as f64)).collect() };
        blocks.add(&wide(&taken.sum), frames);
        if let Some(sums) = session.take_biased()? {
            biased
                .get_or_insert_with(|| BlockBatches::new(size, block))
                .add(&wide(&sums), frames);
        }
        total.absorb(&taken)?;
        progress(b + 1, total.frames as u32);
    }
    Ok(RunBatches {
        blocks,
        biased,
        image: total.image(),
        frames: total.frames as u32,
        seconds: start.elapsed().as_secs_f64(),
        rejected_samples: session.counters.get("samples_rejected").copied().unwrap_or(0),
    })
}

/// Renders exactly `count` frames through the driver.
fn render_frames(session: &mut Session, count: u32) -> Result<u32> {
    drive(
        session,
        Plan::new(DriveBudget::Frames(count as u64)),
        &mut Stopwatch::start(),
        &mut [],
    )?
    .whole("the batch")?;
    Ok(count)
}

/// Renders for `time` (at least one frame) through the driver; returns the frames.
fn render_for(session: &mut Session, time: Duration) -> Result<u32> {
    let first = session.frames;
    let plan = Plan::new(DriveBudget::Time(time)).at_least(1);
    drive(session, plan, &mut Stopwatch::start(), &mut [])?.whole("the batch")?;
    Ok(session.frames - first)
}
