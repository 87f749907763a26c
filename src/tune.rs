//! `--layout auto`: measure every legal layout of a graph on this scene and GPU (the paper's
//! advice, "measure every configuration", done by the tool) for a short screening, then refine
//! the fastest two over the option values that recorded tunings found to matter (workgroup
//! size, pool size), and the fastest of all with wgpu's loop guards the other way. On a GPU,
//! threads compile and instantiate the next layouts while one is measured.

use crate::bench::{Measurement, measure_session};
use crate::run::{Run, Session};
use anyhow::{Result, bail};
use lightgraph_engine::ir::{LayoutDecl, Policy, StateStorage};
use lightgraph_engine::{Gpu, Program};
use std::fmt::Write;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// A layout tried by the tuner, with its measurement or why it failed.
pub struct Trial {
    /// Name (passes per kernel, loop mode, options).
    pub name: String,
    /// The layout.
    pub decl: LayoutDecl,
    /// The measurement, or the error.
    pub result: Result<Measurement, String>,
    /// The program the trial compiled, kept for the fastest trial only (after
    /// [`autotune_with`]), so that a render in its layout takes it instead of compiling the
    /// winner again ([`Run::take_tuned`]).
    pub program: Option<Program>,
}

impl Trial {
    /// Samples per second (0 for a failed trial).
    pub fn score(&self) -> f64 {
        self.result.as_ref().map_or(0.0, |m| m.samples_per_second())
    }
}

fn options_of(decl: &LayoutDecl) -> String {
    let mut s = format!("wg {}", decl.workgroup_size);
    if decl.policy != Policy::Naive {
        let _ = write!(
            s,
            ", {} threads",
            decl.threads.map_or("default".to_string(), |t| t.to_string())
        );
    }
    if decl.kernels.len() > decl.kernels.iter().filter(|k| k.len() == 1).count().min(1) {
        let _ = write!(s, ", {:?}", decl.state);
    }
    if !decl.loop_guards {
        let _ = write!(s, ", loop guards off");
    }
    s
}

/// A trial's name without its options.
fn base_name(name: &str) -> String {
    name.rsplit_once(" (").map_or(name, |(n, _)| n).to_string()
}

/// How the tuner measures.
#[derive(Debug, Clone, Copy)]
pub struct Tuning {
    /// Time each refined layout is measured for; the screening of every legal layout takes
    /// half of it.
    pub budget: Duration,
    /// Threads compiling and instantiating the next layouts while one is measured (0: each in
    /// turn on the measuring thread).
    pub preparers: usize,
}

impl Tuning {
    /// `budget` a layout, with up to eight layouts prepared ahead on a GPU (one a core; eight
    /// took Sponza's tuning from 22.2 to 19.6 s on an H100 against four); none ahead on a CPU
    /// adapter (lavapipe), where compiling beside a measurement would slow the measured device.
    pub fn for_gpu(gpu: &Gpu, budget: Duration) -> Tuning {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        Tuning {
            budget,
            preparers: if gpu.is_cpu() { 0 } else { threads.clamp(1, 8) },
        }
    }
}

/// Workgroup sizes the refinement tries: 64 and 128 beat 32 and 256 by 5-8% in every recorded
/// tuning (docs/performance.md, "`--layout auto`").
const REFINED_WORKGROUPS: [u32; 2] = [64, 128];
/// Pool sizes the refinement tries besides the layout's own: pool sizes from 2^17 to 2^20
/// were within 0.1% of each other on the same records.
const REFINED_POOL: u64 = 1 << 20;
/// Layouts the refinement takes from the screening, fastest first.
const REFINED_LAYOUTS: usize = 2;

/// `--layout auto` of `run` on `gpu`: [`autotune`], then the fastest layout becomes the run's,
/// with the program its trial compiled ([`Run::take_tuned`]), so that the render compiles
/// nothing more. Returns the trials, fastest first (the winner's program moved into the run).
pub fn tune(gpu: &Gpu, run: &mut Run, budget: Duration, report: impl FnMut(&Trial)) -> Result<Vec<Trial>> {
    let mut trials = autotune(gpu, run, budget, report)?;
    let best = &mut trials[0];
    run.take_tuned(gpu, (best.name.clone(), best.decl.clone()), best.program.take());
    Ok(trials)
}

/// [`autotune_with`] with [`Tuning::for_gpu`].
pub fn autotune(gpu: &Gpu, run: &Run, budget: Duration, report: impl FnMut(&Trial)) -> Result<Vec<Trial>> {
    autotune_with(gpu, run, Tuning::for_gpu(gpu, budget), report)
}

/// Screens every legal layout of `run`'s graph for half the budget each, refines the two
/// fastest over workgroup size and pool size (state in SoA) for the whole budget, and tries
/// the fastest of all with the loop guards flipped; returns all trials, fastest first, the
/// first with its compiled program. `report` sees each trial as it finishes.
pub fn autotune_with(gpu: &Gpu, run: &Run, tuning: Tuning, mut report: impl FnMut(&Trial)) -> Result<Vec<Trial>> {
    let graph = &run.graph;
    // The default layout with the tuning profile's knobs: the candidates start from them.
    let default = graph.layouts[&graph.default_layout].clone();
    let base = run
        .options
        .layout
        .tuning
        .apply(Some(gpu), graph, &graph.default_layout, default);
    let candidates = lightgraph_engine::auto::legal_layouts(
        graph,
        &LayoutDecl {
            kernels: Vec::new(),
            ..base
        },
    );
    if candidates.is_empty() {
        bail!("graph '{}' has no legal layout", graph.name);
    }
    let screened = candidates
        .into_iter()
        .map(|(name, decl)| (format!("{name} ({})", options_of(&decl)), decl))
        .collect();
    let mut measuring = Measuring {
        gpu,
        run,
        report: &mut report,
        fastest: 0.0,
    };
    let mut trials = measuring.measure_all(screened, tuning.budget / 2, tuning.preparers);
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    let refined = refinements(run, &trials)?;
    trials.extend(measuring.measure_all(refined, tuning.budget, tuning.preparers));
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    // The fastest once more with wgpu's loop guards the other way (LayoutDecl::loop_guards).
    let (name, decl) = (&trials[0].name, &trials[0].decl);
    let flipped = LayoutDecl {
        loop_guards: !decl.loop_guards,
        ..decl.clone()
    };
    let label = format!("{} ({})", base_name(name), options_of(&flipped));
    trials.extend(measuring.measure_all(vec![(label, flipped)], tuning.budget, 0));
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    // Only the winner's program is wanted (a trial kept one when it was the fastest so far).
    for trial in trials.iter_mut().skip(1) {
        trial.program = None;
    }
    Ok(trials)
}

/// The variants of the fastest screened layouts not measured yet: each of
/// [`REFINED_WORKGROUPS`], with the layout's own pool and [`REFINED_POOL`] where it has one,
/// state in SoA.
fn refinements(run: &Run, trials: &[Trial]) -> Result<Vec<(String, LayoutDecl)>> {
    let mut out: Vec<(String, LayoutDecl)> = Vec::new();
    for t in trials.iter().filter(|t| t.result.is_ok()).take(REFINED_LAYOUTS) {
        let variable = lightgraph_engine::auto::variable(&run.graph, &t.name, &t.decl)?;
        let pools = match variable.pool {
            true => vec![t.decl.threads, Some(REFINED_POOL)],
            false => vec![t.decl.threads],
        };
        for workgroup_size in REFINED_WORKGROUPS {
            for &threads in &pools {
                let variant = LayoutDecl {
                    workgroup_size,
                    threads,
                    state: StateStorage::SoA,
                    ..t.decl.clone()
                };
                let label = format!("{} ({})", base_name(&t.name), options_of(&variant));
                let known = |name: &String| *name == label;
                if !trials.iter().any(|tr| known(&tr.name)) && !out.iter().any(|(n, _)| known(n)) {
                    out.push((label, variant));
                }
            }
        }
    }
    Ok(out)
}

/// The trials' measuring: the run, its GPU, who sees each trial, and the fastest rate so far.
struct Measuring<'a, 'g, R> {
    gpu: &'g Gpu,
    run: &'a Run,
    report: &'a mut R,
    /// Samples per second of the fastest trial so far: a trial faster still keeps its program.
    fastest: f64,
}

impl<R: FnMut(&Trial)> Measuring<'_, '_, R> {
    /// Measures each of `layouts` for `budget` after one warm-up frame; `preparers` threads
    /// compile and instantiate the next ones meanwhile (at most `preparers` waiting), so that
    /// the measuring thread only measures. Trials in the order they were measured.
    fn measure_all(&mut self, layouts: Vec<(String, LayoutDecl)>, budget: Duration, preparers: usize) -> Vec<Trial> {
        let (gpu, run) = (self.gpu, self.run);
        if preparers == 0 {
            return layouts
                .into_iter()
                .map(|(name, decl)| {
                    let session = run.session_in(gpu, &name, &decl);
                    self.finish((name, decl), session, budget)
                })
                .collect();
        }
        let next = AtomicUsize::new(0);
        let (sender, prepared) = mpsc::sync_channel(preparers);
        std::thread::scope(|scope| {
            for _ in 0..preparers.min(layouts.len()) {
                let (sender, next, layouts) = (sender.clone(), &next, &layouts);
                scope.spawn(move || {
                    while let Some((name, decl)) = layouts.get(next.fetch_add(1, Ordering::Relaxed)) {
                        if sender
                            .send((name.clone(), decl.clone(), run.session_in(gpu, name, decl)))
                            .is_err()
                        {
                            break;
                        }
                    }
                });
            }
            drop(sender);
            prepared
                .iter()
                .map(|(name, decl, session)| self.finish((name, decl), session, budget))
                .collect()
        })
    }

    /// The trial of the layout `decl` (called `name`) measured in `session` for `budget`,
    /// with its program where it is the fastest so far; reported.
    fn finish(&mut self, (name, decl): (String, LayoutDecl), session: Result<Session>, budget: Duration) -> Trial {
        let mut program = None;
        let result = session
            .and_then(|mut s| {
                let m = measure_session(&mut s, &name, budget)?;
                if m.samples_per_second() > self.fastest {
                    self.fastest = m.samples_per_second();
                    program = Some(s.program().clone());
                }
                Ok(m)
            })
            .map_err(|e| format!("{e:#}"));
        let trial = Trial {
            name,
            decl,
            result,
            program,
        };
        (self.report)(&trial);
        trial
    }
}

/// The tuner's table as Markdown, fastest first.
pub fn table(trials: &[Trial]) -> String {
    let mut md = String::from(
        "| rank | layout | Msamples/s | Mrays/s | GPU Mrays/s | memory MiB |\n|---|---|---|---|---|---|\n",
    );
    for (i, t) in trials.iter().enumerate() {
        match &t.result {
            Ok(m) => {
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} |",
                    i + 1,
                    t.name,
                    m.samples_per_second() / 1e6,
                    m.rays_per_second() / 1e6,
                    m.gpu_rays_per_second() / 1e6,
                    m.memory_bytes as f64 / 1048576.0
                );
            }
            Err(e) => {
                let _ = writeln!(
                    md,
                    "| – | {} | failed: {} | | | |",
                    t.name,
                    e.replace('|', "/").replace('\n', " ")
                );
            }
        }
    }
    md
}
