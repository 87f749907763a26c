//! One run across machines with MPI (cargo feature `mpi`): one rank per GPU, the rank's
//! node-local index picking its adapter. The run's frames are cut into blocks of [`BLOCK`];
//! rank r renders blocks r, r + ranks, r + 2 ranks, ... (so every rank's share is known
//! without messages, and the union is one run's frames), keeping its own sums in f64. Every
//! [`INTERVAL`] each rank posts a non-blocking all-reduce of a few numbers (blocks and rays
//! per rank, whether it is done), rendering on while it completes; rank 0 shows the progress
//! from it. The sums stay on the GPUs (compensated f32 sums, as in a one-GPU render) and
//! travel once: each rank reads its own back and one reduce adds them on rank 0 after the
//! round in which every rank was done (and every round where a live view wants the film),
//! so a run pays for one read-back and one film reduction, not one every round.

use crate::drive::{Budget, Ended, Executor, Plan, Stopwatch, drive};
use crate::film::Film;
use crate::run::Run;
use crate::run::Session;
use anyhow::{Result, anyhow, bail};
use lightgraph_engine::Gpu;
use mpi::collective::SystemOperation;
use mpi::traits::*;
use std::time::{Duration, Instant};

/// Frames of one block: a rank's unit of work and of its GPU read-backs.
pub const BLOCK: u64 = 16;

/// Time between two reductions of the ranks' sums.
pub const INTERVAL: Duration = Duration::from_secs(2);

/// This process's place in the run.
#[derive(Debug, Clone, Copy)]
pub struct Place {
    /// Rank in the world.
    pub rank: usize,
    /// Ranks in the world.
    pub ranks: usize,
    /// Rank among the ranks of this machine (picks the adapter).
    pub local: usize,
}

/// What a run across ranks did, as rank 0 knows it.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// Frames each rank rendered.
    pub frames_by_rank: Vec<u64>,
    /// Rays each rank traced.
    pub rays_by_rank: Vec<u64>,
    /// Seconds the last film reduction took (the ranks' sums to rank 0, nothing rendering
    /// beside it).
    pub last_reduction_seconds: f64,
    /// Bytes each rank sent in a film reduction.
    pub reduction_bytes: usize,
    /// Seconds from the moment every rank had its session (the budget's clock) to the film
    /// on rank 0: the run's time with its set-up off the clock.
    pub render_seconds: f64,
    /// Seconds rank 0 waited for the rounds' small all-reduces: the ranks' imbalance at the
    /// round ends, plus the messages.
    pub waiting_seconds: f64,
    /// Whether a signal (SIGINT, SIGTERM) on some rank ended the run early: every rank
    /// stopped after its block in flight, and the film holds what they rendered.
    pub interrupted: bool,
}

/// What rank 0 learns at each reduction.
pub struct Progress<'a> {
    /// The run's film so far.
    pub film: &'a Film,
    /// Frames each rank has rendered.
    pub frames_by_rank: &'a [u64],
    /// Rays each rank has traced.
    pub rays_by_rank: &'a [u64],
}

/// The frames of block `j` of a run of `budget`: [j BLOCK, (j + 1) BLOCK), cut at the budget's
/// frames; None past them.
fn block_frames(j: u64, budget: Budget) -> Option<(u64, u64)> {
    let (start, end) = (j * BLOCK, (j + 1) * BLOCK);
    match budget {
        Budget::Frames(total) => (start < total).then(|| (start, end.min(total))),
        Budget::Time(_) => Some((start, end)),
    }
}

/// A rank's state: its session, its own film and its count of blocks.
struct Worker<'g> {
    session: Session<'g>,
    film: Film,
    blocks: u64,
    done: bool,
}

impl Worker<'_> {
    /// Submits this rank's next block, reading back the one before it (the GPU keeps a block
    /// queued while the host records the next); done when the budget has no more for it.
    fn render_block(&mut self, run: &Run, place: Place, budget: Budget, start: Instant) -> Result<()> {
        self.check_budget(place, budget, start);
        if self.done {
            return Ok(());
        }
        let (a, b) = block_frames(self.next_block(place), budget).expect("a block within the budget");
        let first = u32::try_from(run.spec.first_frame + a).map_err(|_| anyhow!("frame index past 2^32"))?;
        self.session.jump_to(first)?;
        self.session.render_frames_behind((b - a) as u32)?;
        self.blocks += 1;
        Ok(())
    }

    /// Marks the rank done when its budget has no block left for it: before a round's
    /// message, so that a rank whose time ran out says so at once.
    fn check_budget(&mut self, place: Place, budget: Budget, start: Instant) {
        let left = match budget {
            Budget::Time(t) => start.elapsed() < t,
            Budget::Frames(_) => block_frames(self.next_block(place), budget).is_some(),
        };
        self.done |= !left;
    }

    /// The index of the run's block this rank renders next.
    fn next_block(&self, place: Place) -> u64 {
        self.blocks * place.ranks as u64 + place.rank as u64
    }

    /// Adds the GPU's sums so far into the rank's f64 film.
    fn absorb(&mut self) -> Result<()> {
        self.film.absorb(&self.session.take_accumulation()?)
    }

    /// The rank's round message: its blocks and the rays read back so far in its own slots of
    /// a vector per rank (zeros elsewhere), then whether it is done and whether a signal
    /// stopped it.
    fn state(&self, place: Place, done: bool, interrupted: bool) -> Vec<f64> {
        let mut v = vec![0.0; 2 * place.ranks + 2];
        v[place.rank] = self.blocks as f64;
        v[place.ranks + place.rank] = self.session.rays() as f64;
        v[2 * place.ranks] = f64::from(u8::from(done));
        v[2 * place.ranks + 1] = f64::from(u8::from(interrupted));
        v
    }

    /// The rank's sums and squared sums, flat.
    fn sums(&self) -> Vec<f64> {
        self.film.sum.iter().chain(&self.film.sum_sq).flat_map(|p| *p).collect()
    }
}

/// Puts a film reduction's sums (`sums`: sums, then squared sums, flat) into rank 0's film.
fn set_sums(film: &mut Film, sums: &[f64]) {
    for (i, p) in film.sum.iter_mut().chain(film.sum_sq.iter_mut()).enumerate() {
        *p = [sums[3 * i], sums[3 * i + 1], sums[3 * i + 2]];
    }
}

/// Sets rank 0's film's frame ranges from a round's all-reduced state (blocks per rank); returns
/// the frames and rays of each rank.
fn set_ranges(film: &mut Film, state: &[f64], run: &Run, place: Place, budget: Budget) -> Result<(Vec<u64>, Vec<u64>)> {
    let mut ranges = Vec::new();
    let mut frames_by_rank = vec![0; place.ranks];
    for (r, frames) in frames_by_rank.iter_mut().enumerate() {
        for k in 0..state[r] as u64 {
            let (a, b) = block_frames(k * place.ranks as u64 + r as u64, budget).expect("a rendered block");
            ranges.push((run.spec.first_frame + a, run.spec.first_frame + b));
            *frames += b - a;
        }
    }
    film.set_ranges(ranges)?;
    let rays = state[place.ranks..2 * place.ranks].iter().map(|&x| x as u64).collect();
    Ok((frames_by_rank, rays))
}

/// Where this process is: rank, ranks, and its index among the ranks of its machine.
pub fn place(world: &impl Communicator) -> Place {
    let node = world.split_shared(world.rank());
    Place {
        rank: world.rank() as usize,
        ranks: world.size() as usize,
        local: node.rank() as usize,
    }
}

/// The adapter of the rank at `place`: `adapter` if given, else its node-local index (more
/// ranks than GPUs on a machine share them in turn).
pub fn rank_adapter(place: &Place, adapter: Option<&str>) -> String {
    let adapters = lightgraph_engine::gpu::adapters().len().max(1);
    adapter.map_or_else(|| (place.local % adapters).to_string(), String::from)
}

/// Opens this rank's session for `run` on `gpu` (the rank's GPU, or why it did not open); a
/// rank that cannot ends the whole job (the other ranks would wait in collectives), with its
/// error.
fn open_worker<'g, C: Communicator>(
    world: &C,
    gpu: Result<&'g Gpu>,
    run: &Run,
    place: Place,
    film: &Film,
) -> Worker<'g> {
    let session = gpu.and_then(|gpu| run.session(gpu));
    match session {
        Ok(session) => Worker {
            session,
            film: Film::new(film.size, film.info.clone()),
            blocks: 0,
            done: false,
        },
        Err(e) => {
            eprintln!("error: rank {}: {e:#}", place.rank);
            world.abort(1)
        }
    }
}

/// Renders `run` within `budget` on every rank of `world`, each on its adapter (`adapter`, or
/// the rank's node-local index): the driver's loop over [`Ranks`], one round a batch. Rank 0
/// gets `progress` after every round and the run's film in `film` at the end, and after every
/// round too where `live` (the same on every rank: a live view wants the film); the other
/// ranks leave `film` empty. Returns what the ranks did (on rank 0; zeros elsewhere but the
/// times).
pub fn render_across<C: Communicator>(
    world: &C,
    run: &Run,
    adapter: Option<&str>,
    budget: Budget,
    live: bool,
    film: &mut Film,
    mut progress: impl FnMut(&Progress),
) -> Result<Outcome> {
    let place = place(world);
    let gpu = Gpu::new(Some(&rank_adapter(&place, adapter)));
    let worker = open_worker(world, gpu.as_ref().map_err(|e| anyhow!("{e}")), run, place, film);
    world.barrier();
    let mut ranks = Ranks {
        world,
        run,
        place,
        budget,
        live,
        worker,
        film,
        outcome: Outcome {
            frames_by_rank: vec![0; place.ranks],
            rays_by_rank: vec![0; place.ranks],
            ..Default::default()
        },
        failure: None,
        start: Instant::now(),
        rounds: 0,
        finished: false,
    };
    let mut show = |r: &mut Ranks<C>, _: &mut Stopwatch| -> Result<()> {
        if r.place.rank == 0 {
            progress(&Progress {
                film: r.film,
                frames_by_rank: &r.outcome.frames_by_rank,
                rays_by_rank: &r.outcome.rays_by_rank,
            });
        }
        Ok(())
    };
    drive(&mut ranks, Plan::new(budget), &mut Stopwatch::start(), &mut [&mut show])?;
    ranks.outcome.render_seconds = ranks.start.elapsed().as_secs_f64();
    if let Some(e) = ranks.failure {
        bail!("rank {}: {e:#}", place.rank);
    }
    Ok(ranks.outcome)
}

/// The ranks as the driver's executor, seen from one of them: each batch is a round (render
/// blocks while a small all-reduce of every rank's state completes); the ranks decide the end
/// together, in the round where every one is done.
struct Ranks<'a, 'g, C> {
    world: &'a C,
    run: &'a Run,
    place: Place,
    budget: Budget,
    live: bool,
    worker: Worker<'g>,
    film: &'a mut Film,
    outcome: Outcome,
    failure: Option<anyhow::Error>,
    /// When every rank had its session: the budget's clock.
    start: Instant,
    rounds: u32,
    /// Whether the last round found every rank done.
    finished: bool,
}

impl<C: Communicator> Executor for Ranks<'_, '_, C> {
    fn frames(&self) -> u64 {
        self.outcome.frames_by_rank.iter().sum()
    }

    /// One round: this rank's state posted, blocks rendered until the round's end, the
    /// ranks' states read; the film reduced when all are done (or a live view wants it).
    fn advance(&mut self, _left: Option<Duration>, _max: u64) -> Result<()> {
        let (place, world) = (self.place, self.world);
        self.rounds += 1;
        let interrupted_here = crate::interrupt::requested().is_some();
        let worker = &mut self.worker;
        worker.done |= interrupted_here;
        worker.check_budget(place, self.budget, self.start);
        let state = worker.state(place, worker.done || self.failure.is_some(), interrupted_here);
        let mut all = vec![0.0; state.len()];
        let (failure, start, round, run, budget) = (&mut self.failure, self.start, self.rounds, self.run, self.budget);
        let waited = mpi::request::scope(|scope| {
            let request = world.immediate_all_reduce_into(scope, &state[..], &mut all[..], SystemOperation::sum());
            // Render on while the message completes, until the round's end.
            while failure.is_none() && !worker.done && start.elapsed() < INTERVAL * round {
                if let Err(e) = worker.render_block(run, place, budget, start) {
                    *failure = Some(e);
                }
            }
            let waiting = Instant::now();
            request.wait();
            waiting.elapsed().as_secs_f64()
        });
        self.outcome.waiting_seconds += waited;
        let all_done = all[2 * place.ranks] as usize == place.ranks;
        if all_done || self.live {
            if let Err(e) = worker.absorb() {
                eprintln!("error: rank {}: {e:#}", place.rank);
                world.abort(1)
            }
            reduce_film(world, worker, self.film, &mut self.outcome);
        }
        if place.rank == 0 {
            (self.outcome.frames_by_rank, self.outcome.rays_by_rank) = set_ranges(self.film, &all, run, place, budget)?;
        }
        if all[2 * place.ranks + 1] > 0.0 {
            // A signal on some rank: every rank's next message is its last.
            self.outcome.interrupted = true;
            worker.done = true;
        }
        self.finished = all_done;
        Ok(())
    }

    /// Every round ends with its blocks read back where the film is reduced.
    fn settle(&mut self) -> Result<()> {
        Ok(())
    }

    /// Over in the round where every rank was done: at the budget, a failure or a signal on
    /// any rank (then [`Outcome::interrupted`]; the signal may have come to another rank).
    fn ended(&self, _plan: &Plan, _done: u64, _clock: &Stopwatch) -> Option<Ended> {
        self.finished.then_some(Ended::Done)
    }
}

/// Reduces every rank's sums into rank 0's film (blocking), timing it into `outcome`.
fn reduce_film<C: Communicator>(world: &C, worker: &Worker, film: &mut Film, outcome: &mut Outcome) {
    let root = world.process_at_rank(0);
    let sums = worker.sums();
    let started = Instant::now();
    if world.rank() == 0 {
        let mut total = vec![0.0; sums.len()];
        root.reduce_into_root(&sums[..], &mut total[..], SystemOperation::sum());
        set_sums(film, &total);
    } else {
        root.reduce_into(&sums[..], SystemOperation::sum());
    }
    outcome.last_reduction_seconds = started.elapsed().as_secs_f64();
    outcome.reduction_bytes = 8 * sums.len();
}
