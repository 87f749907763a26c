//! One run across machines with MPI (cargo feature `mpi`): one rank per GPU, the rank's
//! node-local index picking its adapter. The run's frames are cut into blocks of [`BLOCK`];
//! rank r renders blocks r, r + ranks, r + 2 ranks, ... (so every rank's share is known
//! without messages, and the union is one run's frames), keeping its own sums in f64. Every
//! [`INTERVAL`] each rank posts a non-blocking reduce of its sums to rank 0 and a
//! non-blocking all-reduce of whether it is done, and renders on while they complete; rank 0
//! rebuilds the run's film from each reduce (progress, and the output at the end). The loop
//! ends after the reduce in which every rank was done.

use crate::multi::{Budget, Run};
use crate::reference::Reference;
use crate::render::Session;
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
    /// Seconds the last reduction took to complete (no rendering beside it): the time of one
    /// film reduction.
    pub last_reduction_seconds: f64,
    /// Bytes each rank sent in a reduction.
    pub reduction_bytes: usize,
    /// Whether a signal (SIGINT, SIGTERM) on some rank ended the run early: every rank
    /// stopped after its block in flight, and the film holds what they rendered.
    pub interrupted: bool,
}

/// What rank 0 learns at each reduction.
pub struct Progress<'a> {
    /// The run's film so far.
    pub film: &'a Reference,
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
    film: Reference,
    blocks: u64,
    rays: u64,
    done: bool,
}

impl Worker<'_> {
    /// Renders this rank's next block; done when the budget has no more for it.
    fn render_block(&mut self, run: &Run, place: Place, budget: Budget, start: Instant) -> Result<()> {
        let j = self.blocks * place.ranks as u64 + place.rank as u64;
        let frames = match (budget, block_frames(j, budget)) {
            (Budget::Time(t), _) if start.elapsed() >= t => None,
            (_, f) => f,
        };
        let Some((a, b)) = frames else {
            self.done = true;
            return Ok(());
        };
        let first = u32::try_from(run.first_frame + a).map_err(|_| anyhow!("frame index past 2^32"))?;
        self.session.jump_to(first)?;
        let stats = self.session.render_frames((b - a) as u32)?;
        self.rays += stats
            .counters
            .iter()
            .filter(|(k, _)| k.starts_with("rays_"))
            .map(|(_, v)| v)
            .sum::<u64>();
        self.blocks += 1;
        Ok(())
    }

    /// The rank's contribution to a reduction: its sums (the GPU's taken over first), then its
    /// blocks and rays in its own slots of a vector per rank (zeros elsewhere).
    fn snapshot(&mut self, place: Place) -> Result<Vec<f64>> {
        self.film.absorb(&self.session.take_accumulation()?)?;
        let mut v: Vec<f64> = self.film.sum.iter().chain(&self.film.sum_sq).flat_map(|p| *p).collect();
        let mut slots = vec![0.0; 2 * place.ranks];
        slots[place.rank] = self.blocks as f64;
        slots[place.ranks + place.rank] = self.rays as f64;
        v.extend(slots);
        Ok(v)
    }
}

/// Rebuilds the run's film on rank 0 from a reduction (`sums`) into `film`; returns the frames
/// and rays of each rank.
fn rebuild(
    film: &mut Reference,
    sums: &[f64],
    run: &Run,
    place: Place,
    budget: Budget,
) -> Result<(Vec<u64>, Vec<u64>)> {
    let n = film.sum.len();
    for (i, p) in film.sum.iter_mut().chain(film.sum_sq.iter_mut()).enumerate() {
        *p = [sums[3 * i], sums[3 * i + 1], sums[3 * i + 2]];
    }
    let slots = &sums[6 * n..];
    let mut ranges = Vec::new();
    let mut frames_by_rank = vec![0; place.ranks];
    for (r, frames) in frames_by_rank.iter_mut().enumerate() {
        for k in 0..slots[r] as u64 {
            let (a, b) = block_frames(k * place.ranks as u64 + r as u64, budget).expect("a rendered block");
            ranges.push((run.first_frame + a, run.first_frame + b));
            *frames += b - a;
        }
    }
    film.set_ranges(ranges)?;
    let rays = slots[place.ranks..].iter().map(|&x| x as u64).collect();
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

/// Renders `run` within `budget` on every rank of `world`, each on its adapter (`adapter`, or
/// the rank's node-local index). Rank 0 gets the run's film in `film` and `progress` after
/// every reduction; the other ranks leave `film` empty. Returns what the ranks did (on rank
/// 0; zeros elsewhere).
pub fn render_across<C: Communicator>(
    world: &C,
    run: &Run,
    adapter: Option<&str>,
    budget: Budget,
    film: &mut Reference,
    mut progress: impl FnMut(&Progress),
) -> Result<Outcome> {
    let place = place(world);
    let selector = rank_adapter(&place, adapter);
    let (layout, decl) = run.layout;
    let opened = Gpu::new(Some(&selector)).map_err(anyhow::Error::from);
    let session = opened
        .as_ref()
        .map_err(|e| anyhow!("{e}"))
        .and_then(|gpu| Session::with_layout(gpu, run.graph, layout, decl.clone(), run.scene, run.options.clone()));
    let session = match session {
        Ok(s) => s,
        Err(e) => {
            // The other ranks wait in collectives: end the whole job.
            eprintln!("error: rank {}: {e:#}", place.rank);
            world.abort(1)
        }
    };
    let mut worker = Worker {
        session,
        film: Reference::new(film.size, film.info.clone()),
        blocks: 0,
        rays: 0,
        done: false,
    };
    let root = world.process_at_rank(0);
    world.barrier();
    let start = Instant::now();
    let mut outcome = Outcome {
        frames_by_rank: vec![0; place.ranks],
        rays_by_rank: vec![0; place.ranks],
        ..Default::default()
    };
    let mut failure: Option<anyhow::Error> = None;
    for round in 1u32.. {
        let interrupted_here = crate::interrupt::requested().is_some();
        if interrupted_here {
            worker.done = true;
        }
        let snapshot = match worker.snapshot(place) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("error: rank {}: {e:#}", place.rank);
                world.abort(1)
            }
        };
        let mut sums = vec![0.0; snapshot.len()];
        // Ranks done, and ranks a signal stopped (all stop once one did).
        let done_here = [u32::from(worker.done || failure.is_some()), u32::from(interrupted_here)];
        let mut done_ranks = [0u32; 2];
        mpi::request::scope(|scope| {
            let films = if place.rank == 0 {
                root.immediate_reduce_into_root(scope, &snapshot[..], &mut sums[..], SystemOperation::sum())
            } else {
                root.immediate_reduce_into(scope, &snapshot[..], SystemOperation::sum())
            };
            let done =
                world.immediate_all_reduce_into(scope, &done_here[..], &mut done_ranks[..], SystemOperation::sum());
            // Render on while the reductions complete, until the next round.
            while failure.is_none() && !worker.done && start.elapsed() < INTERVAL * round {
                if let Err(e) = worker.render_block(run, place, budget, start) {
                    failure = Some(e);
                }
            }
            let waited = Instant::now();
            films.wait();
            done.wait();
            outcome.last_reduction_seconds = waited.elapsed().as_secs_f64();
        });
        outcome.reduction_bytes = 8 * snapshot.len();
        if place.rank == 0 {
            (outcome.frames_by_rank, outcome.rays_by_rank) = rebuild(film, &sums, run, place, budget)?;
            progress(&Progress {
                film,
                frames_by_rank: &outcome.frames_by_rank,
                rays_by_rank: &outcome.rays_by_rank,
            });
        }
        if done_ranks[1] > 0 {
            // A signal on some rank: every rank's next snapshot is its last.
            outcome.interrupted = true;
            worker.done = true;
        }
        if done_ranks[0] as usize == place.ranks {
            break;
        }
        if worker.done || failure.is_some() {
            // Wait for the others at the next round without spinning.
            std::thread::sleep((INTERVAL * round).saturating_sub(start.elapsed()));
        }
    }
    if let Some(e) = failure {
        bail!("rank {}: {e:#}", place.rank);
    }
    Ok(outcome)
}
