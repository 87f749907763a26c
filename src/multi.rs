//! One run on several GPUs of a machine: a device and a thread per GPU, each rendering
//! batches of frames it claims from a shared counter, so a faster GPU takes more frames (each
//! batch is sized from its own measured frame time); every few seconds each GPU hands its
//! sums to the host, which adds them into one film. The frames are those of a one-GPU run with the same settings, so
//! the film equals that run's to float rounding.

pub use crate::drive::Budget;
use crate::drive::{Ended, Executor, Plan, Stopwatch, drive};
use crate::film::Film;
use crate::run::{Run, Session};
use anyhow::{Result, anyhow, bail};
use lightgraph_engine::Gpu;
use lightgraph_engine::runtime::MAX_BATCH;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Barrier, OnceLock};
use std::time::{Duration, Instant};

/// How long a batch of one GPU should take: short enough for a balanced end and a live
/// film, long enough that reading its sums back costs little.
const BATCH_TIME: Duration = Duration::from_millis(500);

/// How often a GPU hands its sums to the host (and the progress line moves).
const SEND_EVERY: Duration = Duration::from_secs(2);

/// How long the run took once every GPU was ready, and the host's time adding the GPUs'
/// batches into the film.
#[derive(Debug, Clone, Default)]
pub struct Merging {
    /// Seconds from the moment every GPU had its session (set-up excluded) to the last batch.
    pub run_seconds: f64,
    /// Batches added.
    pub batches: u64,
    /// Seconds spent adding them.
    pub seconds: f64,
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
    /// Seconds it spent rendering and handing over its batches (set-up excluded).
    pub busy_seconds: f64,
}

impl Share {
    /// Its frames per second of rendering.
    pub fn frames_per_second(&self) -> f64 {
        self.frames as f64 / self.busy_seconds.max(1e-9)
    }
}

/// The adapters `--gpus` names: `all`, the first N, or a comma-separated list of indices, PCI
/// bus ids or names (one may repeat: several devices of one adapter).
pub fn gpu_selectors(spec: &str) -> Result<Vec<String>> {
    let adapters = lightgraph_engine::gpu::adapters();
    let listed = || {
        adapters
            .iter()
            .enumerate()
            .map(|(i, a)| lightgraph_engine::gpu::describe_adapter(i, a))
            .collect::<Vec<_>>()
            .join("; ")
    };
    let count = match spec.trim() {
        "all" => adapters.len(),
        s if !s.contains(',') => match s.parse::<usize>() {
            Ok(n) => n,
            Err(_) => return Ok(vec![s.to_string()]),
        },
        s => {
            return Ok(s
                .split(',')
                .map(|x| x.trim().to_string())
                .filter(|x| !x.is_empty())
                .collect());
        }
    };
    if count == 0 || count > adapters.len() {
        bail!(
            "--gpus {spec}: this machine has {} adapters: {}",
            adapters.len(),
            listed()
        );
    }
    Ok((0..count).map(|i| i.to_string()).collect())
}

/// A message from a GPU's thread.
enum Message {
    /// The adapter opened: its description.
    Opened(usize, String),
    /// A GPU's sums since its last message, with the rays and the seconds it rendered.
    Batch(usize, crate::run::Accumulation, u64, f64),
    /// The thread stopped with an error.
    Failed(usize, anyhow::Error),
}

/// The frames still to hand out, shared by the GPUs' threads.
struct Claims {
    next: AtomicU64,
    budget: Budget,
    /// When every GPU had its session: the budget's clock starts there.
    start: OnceLock<Instant>,
    /// Where the GPUs' threads wait for each other's set-up.
    ready: Barrier,
    stop: AtomicBool,
}

impl Claims {
    /// Waits until every GPU's thread is ready (or gave up), then starts the clock.
    fn wait_ready(&self) {
        self.ready.wait();
        self.started();
    }

    /// When the clock started (now, if it had not).
    fn started(&self) -> Instant {
        *self.start.get_or_init(Instant::now)
    }

    /// The time a timed run has left (None for a run of frames).
    fn left(&self) -> Option<Duration> {
        match self.budget {
            Budget::Time(t) => Some(t.saturating_sub(self.started().elapsed())),
            Budget::Frames(_) => None,
        }
    }

    /// Up to `n` frames (offsets from the run's first frame), or None when the budget is
    /// spent, a thread failed or a signal asked the run to stop (the batches claimed before
    /// still finish, so the film's frames stay contiguous).
    fn claim(&self, n: u64) -> Option<(u64, u64)> {
        if self.stop.load(Ordering::Relaxed) || crate::interrupt::requested().is_some() {
            return None;
        }
        match self.budget {
            Budget::Time(t) => (self.started().elapsed() < t).then(|| (self.next.fetch_add(n, Ordering::Relaxed), n)),
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
/// calling `progress` with the GPUs' shares after each: the host's side is the driver's loop
/// over [`Gpus`]. Returns the shares and the host's time adding batches.
pub fn render_on_gpus(
    run: &Run,
    selectors: &[String],
    budget: Budget,
    film: &mut Film,
    mut progress: impl FnMut(&[Share], &Film),
) -> Result<(Vec<Share>, Merging)> {
    let claims = Claims {
        next: AtomicU64::new(0),
        budget,
        start: OnceLock::new(),
        ready: Barrier::new(selectors.len()),
        stop: AtomicBool::new(false),
    };
    let (tx, rx) = mpsc::channel();
    let mut gpus = Gpus {
        rx,
        open: true,
        claims: &claims,
        selectors,
        film,
        shares: vec![Share::default(); selectors.len()],
        merging: Merging::default(),
        failure: None,
    };
    let mut show = |g: &mut Gpus, _: &mut Stopwatch| -> Result<()> {
        progress(&g.shares, g.film);
        Ok(())
    };
    let driven = std::thread::scope(|scope| {
        for (i, selector) in selectors.iter().enumerate() {
            let (tx, claims) = (tx.clone(), &claims);
            scope.spawn(move || {
                if let Err(e) = gpu_thread(i, selector, run, claims, &tx) {
                    // A thread that failed before the barrier still lets the others pass.
                    claims.stop.store(true, Ordering::Relaxed);
                    let _ = tx.send(Message::Failed(i, e));
                }
            });
        }
        drop(tx);
        drive(&mut gpus, Plan::new(budget), &mut Stopwatch::start(), &mut [&mut show])
    });
    gpus.merging.run_seconds = claims.started().elapsed().as_secs_f64();
    driven?;
    match gpus.failure {
        Some(e) => Err(e),
        None => Ok((gpus.shares, gpus.merging)),
    }
}

/// The GPUs' threads as the driver's executor: each batch is one message of a GPU, added into
/// the film; the threads share the budget through [`Claims`], so the drive ends when the last
/// thread has stopped.
struct Gpus<'a> {
    rx: mpsc::Receiver<Message>,
    /// Whether a thread may still send.
    open: bool,
    claims: &'a Claims,
    selectors: &'a [String],
    film: &'a mut Film,
    shares: Vec<Share>,
    merging: Merging,
    failure: Option<anyhow::Error>,
}

impl Gpus<'_> {
    /// Takes one message of a GPU's thread.
    fn take(&mut self, message: Message) {
        match message {
            Message::Opened(i, adapter) => self.shares[i].adapter = adapter,
            Message::Batch(i, taken, rays, seconds) => {
                let added = Instant::now();
                let absorbed = self.film.absorb(&taken);
                self.merging.batches += 1;
                self.merging.seconds += added.elapsed().as_secs_f64();
                if let Err(e) = absorbed {
                    self.claims.stop.store(true, Ordering::Relaxed);
                    self.failure.get_or_insert(e);
                }
                let share = &mut self.shares[i];
                share.frames += taken.frames as u64;
                share.rays += rays;
                share.busy_seconds += seconds;
            }
            Message::Failed(i, e) => {
                self.failure
                    .get_or_insert(e.context(format!("GPU {i} ('{}')", self.selectors[i])));
            }
        }
    }
}

impl Executor for Gpus<'_> {
    fn frames(&self) -> u64 {
        self.film.frames
    }

    /// Waits for the next batch of a GPU's thread (the threads claim their frames), or for
    /// the last thread to stop.
    fn advance(&mut self, _left: Option<Duration>, _max: u64) -> Result<()> {
        loop {
            match self.rx.recv() {
                Ok(message) => {
                    let batch = matches!(message, Message::Batch(..));
                    self.take(message);
                    if batch {
                        return Ok(());
                    }
                }
                Err(_) => {
                    self.open = false;
                    return Ok(());
                }
            }
        }
    }

    fn settle(&mut self) -> Result<()> {
        while let Ok(message) = self.rx.recv() {
            self.take(message);
        }
        self.open = false;
        Ok(())
    }

    /// Over when every thread has stopped: at the budget, a failure or a signal.
    fn ended(&self, _plan: &Plan, _done: u64, _clock: &Stopwatch) -> Option<Ended> {
        match (self.open, crate::interrupt::requested()) {
            (true, _) => None,
            (false, Some(signal)) => Some(Ended::Signal(signal)),
            (false, None) => Some(Ended::Done),
        }
    }
}

/// One GPU's thread: opens the adapter and a session, then renders claimed batches
/// ([`batch_frames`]), one queued on the GPU while the host records the next, and hands its
/// sums to the host after its first batch (so that a checkpoint, a preview and an interrupted run
/// hold frames early), then every [`SEND_EVERY`] and at the end (the GPU keeps accumulating
/// between: a read-back per batch cost 8% of the rate on an H200).
fn gpu_thread(i: usize, selector: &str, run: &Run, claims: &Claims, tx: &mpsc::Sender<Message>) -> Result<()> {
    let gpu = Gpu::new(Some(selector)).map_err(anyhow::Error::from);
    let session = gpu.as_ref().map_err(|e| anyhow!("{e}")).and_then(|gpu| {
        let _ = tx.send(Message::Opened(i, gpu.describe()));
        run.session(gpu)
    });
    claims.wait_ready();
    let mut session = session?;
    let began = Instant::now();
    let (mut rays_sent, mut sent_at, mut sent) = (0u64, began, false);
    loop {
        let claimed = claims.claim(batch_frames(&session, began, claims.left()));
        if let Some((offset, count)) = claimed {
            let first = u32::try_from(run.spec.first_frame + offset)
                .map_err(|_| anyhow!("frame index {} is past 2^32", run.spec.first_frame + offset))?;
            session.jump_to(first)?;
            session.render_frames_behind(count as u32)?;
        }
        if claimed.is_none() || !sent || sent_at.elapsed() >= SEND_EVERY {
            let taken = session.take_accumulation()?;
            let (rays, busy) = (session.rays(), sent_at.elapsed().as_secs_f64());
            if tx.send(Message::Batch(i, taken, rays - rays_sent, busy)).is_err() {
                return Ok(());
            }
            (rays_sent, sent_at, sent) = (rays, Instant::now(), true);
        }
        if claimed.is_none() {
            return Ok(());
        }
    }
}

/// Frames of a GPU's next claim: about [`BATCH_TIME`] at its measured wall-clock time a frame
/// since it `began` (one group of frames until a frame is read back), no more than a timed
/// run has `left` beyond the frames queued, in whole groups of the frames the GPU renders
/// as one.
fn batch_frames(session: &Session, began: Instant, left: Option<Duration>) -> u64 {
    let at_once = session.frames_at_once() as u64;
    if session.settled == 0 {
        return at_once;
    }
    let per_frame = began.elapsed().as_secs_f64().max(1e-6) / session.settled as f64;
    let queued = (session.frames - session.settled) as f64 * per_frame;
    let room = left.map_or(BATCH_TIME.as_secs_f64(), |t| {
        (t.as_secs_f64() - queued).min(BATCH_TIME.as_secs_f64())
    });
    at_once * (room / (per_frame * at_once as f64)).clamp(1.0, MAX_BATCH as f64) as u64
}
