//! One run on several GPUs of a machine: a device and a thread per GPU, each rendering
//! batches of frames it claims from a shared counter, so a faster GPU takes more frames (each
//! batch is sized from its own measured frame time); the host adds every batch's sums into
//! one film as they arrive. The frames are those of a one-GPU run with the same settings, so
//! the film equals that run's to float rounding.

use crate::reference::Reference;
use crate::render::{LoadedScene, Session, SessionOptions};
use anyhow::{Result, anyhow};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::runtime::MAX_BATCH;
use lightgraph_engine::{Gpu, Graph};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// How long a batch of one GPU should take: short enough for a balanced end and a live
/// film, long enough that reading its sums back costs little.
const BATCH_TIME: Duration = Duration::from_millis(250);

/// How much to render: a number of frames, or a wall-clock time.
#[derive(Debug, Clone, Copy)]
pub enum Budget {
    /// Frames in all.
    Frames(u64),
    /// Wall-clock time.
    Time(Duration),
}

/// What one GPU has done so far.
#[derive(Debug, Clone, Default)]
pub struct Share {
    /// The adapter's description.
    pub adapter: String,
    /// Frames it rendered.
    pub frames: u64,
    /// Rays it traced (the graph's `rays_*` counters).
    pub rays: u64,
    /// Seconds it spent rendering its batches (set-up excluded).
    pub busy_seconds: f64,
}

impl Share {
    /// Its frames per second of rendering.
    pub fn frames_per_second(&self) -> f64 {
        self.frames as f64 / self.busy_seconds.max(1e-9)
    }
}

/// One run of a graph, to be shared by GPUs.
pub struct Run<'a> {
    /// The graph.
    pub graph: &'a Graph,
    /// The layout's name and declaration.
    pub layout: (&'a str, &'a LayoutDecl),
    /// The scene.
    pub scene: &'a LoadedScene,
    /// Session options (resolution, samples per frame, seed, constants).
    pub options: &'a SessionOptions,
    /// Frame index of the run's first frame.
    pub first_frame: u64,
}

/// A message from a GPU's thread.
enum Message {
    /// The adapter opened: its description.
    Opened(usize, String),
    /// A batch's sums, rays and render seconds.
    Batch(usize, crate::render::Accumulation, u64, f64),
    /// The thread stopped with an error.
    Failed(usize, anyhow::Error),
}

/// The frames still to hand out, shared by the GPUs' threads.
struct Claims {
    next: AtomicU64,
    budget: Budget,
    start: Instant,
    stop: AtomicBool,
}

impl Claims {
    /// Up to `n` frames (offsets from the run's first frame), or None when the budget is
    /// spent or a thread failed.
    fn claim(&self, n: u64) -> Option<(u64, u64)> {
        if self.stop.load(Ordering::Relaxed) {
            return None;
        }
        match self.budget {
            Budget::Time(t) => (self.start.elapsed() < t).then(|| (self.next.fetch_add(n, Ordering::Relaxed), n)),
            Budget::Frames(total) => {
                let mut current = self.next.load(Ordering::Relaxed);
                loop {
                    let take = n.min(total.saturating_sub(current));
                    if take == 0 {
                        return None;
                    }
                    match self
                        .next
                        .compare_exchange(current, current + take, Ordering::Relaxed, Ordering::Relaxed)
                    {
                        Ok(_) => return Some((current, take)),
                        Err(seen) => current = seen,
                    }
                }
            }
        }
    }
}

/// Renders `run` on the adapters `selectors` (see [`Gpu::new`]; one may repeat: two
/// devices of one adapter) within `budget`, adding every batch into `film` as it arrives and
/// calling `progress` with the GPUs' shares after each. Returns the shares.
pub fn render_on_gpus(
    run: &Run,
    selectors: &[String],
    budget: Budget,
    film: &mut Reference,
    mut progress: impl FnMut(&[Share], &Reference),
) -> Result<Vec<Share>> {
    let claims = Claims {
        next: AtomicU64::new(0),
        budget,
        start: Instant::now(),
        stop: AtomicBool::new(false),
    };
    let mut shares = vec![Share::default(); selectors.len()];
    let (tx, rx) = mpsc::channel();
    let mut failure = None;
    std::thread::scope(|scope| {
        for (i, selector) in selectors.iter().enumerate() {
            let (tx, claims) = (tx.clone(), &claims);
            scope.spawn(move || {
                if let Err(e) = gpu_thread(i, selector, run, claims, &tx) {
                    claims.stop.store(true, Ordering::Relaxed);
                    let _ = tx.send(Message::Failed(i, e));
                }
            });
        }
        drop(tx);
        for message in rx {
            match message {
                Message::Opened(i, adapter) => shares[i].adapter = adapter,
                Message::Batch(i, taken, rays, seconds) => {
                    if let Err(e) = film.absorb(&taken) {
                        claims.stop.store(true, Ordering::Relaxed);
                        failure.get_or_insert(e);
                    }
                    shares[i].frames += taken.frames as u64;
                    shares[i].rays += rays;
                    shares[i].busy_seconds += seconds;
                    progress(&shares, film);
                }
                Message::Failed(i, e) => {
                    failure.get_or_insert(e.context(format!("GPU {i} ('{}')", selectors[i])));
                }
            }
        }
    });
    match failure {
        Some(e) => Err(e),
        None => Ok(shares),
    }
}

/// One GPU's thread: opens the adapter and a session, then renders claimed batches, each
/// sized to take about [`BATCH_TIME`] at the GPU's own measured frame time.
fn gpu_thread(i: usize, selector: &str, run: &Run, claims: &Claims, tx: &mpsc::Sender<Message>) -> Result<()> {
    let gpu = Gpu::new(Some(selector))?;
    let _ = tx.send(Message::Opened(i, gpu.describe()));
    let (layout, decl) = run.layout;
    let mut session = Session::with_layout(&gpu, run.graph, layout, decl.clone(), run.scene, run.options.clone())?;
    let mut frame_seconds: Option<f64> = None;
    loop {
        let n = match frame_seconds {
            None => 1,
            Some(t) => (BATCH_TIME.as_secs_f64() / t.max(1e-6)).clamp(1.0, MAX_BATCH as f64) as u64,
        };
        let Some((offset, count)) = claims.claim(n) else {
            return Ok(());
        };
        let first = u32::try_from(run.first_frame + offset)
            .map_err(|_| anyhow!("frame index {} is past 2^32", run.first_frame + offset))?;
        session.jump_to(first)?;
        let started = Instant::now();
        let stats = session.render_frames(count as u32)?;
        let taken = session.take_accumulation()?;
        let seconds = started.elapsed().as_secs_f64();
        frame_seconds = Some(seconds / count as f64);
        let rays = stats
            .counters
            .iter()
            .filter(|(k, _)| k.starts_with("rays_"))
            .map(|(_, v)| v)
            .sum();
        if tx.send(Message::Batch(i, taken, rays, seconds)).is_err() {
            return Ok(());
        }
    }
}
