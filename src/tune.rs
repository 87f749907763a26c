//! `--layout auto`: measure every legal layout of a graph on this scene and GPU (the paper's
//! advice, "measure every configuration", done by the tool), then refine the fastest few over
//! option values (workgroup size, pool size, state storage), and the fastest of all with wgpu's
//! loop guards the other way.

use crate::bench::{Measurement, measure};
use crate::run::Run;
use anyhow::{Result, bail};
use lightgraph_engine::Gpu;
use lightgraph_engine::ir::{LayoutDecl, Policy, StateStorage};
use std::fmt::Write;
use std::time::Duration;

/// A layout tried by the tuner, with its measurement or why it failed.
pub struct Trial {
    /// Name (passes per kernel, loop mode, options).
    pub name: String,
    /// The layout.
    pub decl: LayoutDecl,
    /// The measurement, or the error.
    pub result: Result<Measurement, String>,
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

/// Measures every legal layout of `run`'s graph for `budget` each, then the three fastest over option values
/// and the fastest of all with the loop guards flipped;
/// returns all trials, fastest first. `report` sees each trial as it finishes.
pub fn autotune(gpu: &Gpu, run: &Run, budget: Duration, mut report: impl FnMut(&Trial)) -> Result<Vec<Trial>> {
    let (graph, scene, options) = (&run.graph, &run.scene, &run.options);
    let base = graph.layouts[&graph.default_layout].clone();
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
    let mut trials = Vec::new();
    let mut run = |name: String, decl: LayoutDecl, trials: &mut Vec<Trial>| {
        let result =
            measure(gpu, graph, &name, decl.clone(), scene, options.clone(), budget).map_err(|e| format!("{e:#}"));
        let trial = Trial { name, decl, result };
        report(&trial);
        trials.push(trial);
    };
    for (name, decl) in candidates {
        let name = format!("{name} ({})", options_of(&decl));
        run(name, decl, &mut trials);
    }
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    let best: Vec<(String, LayoutDecl)> = trials
        .iter()
        .take(3)
        .map(|t| (t.name.clone(), t.decl.clone()))
        .collect();
    for (name, decl) in best {
        let base = base_name(&name);
        let variable = lightgraph_engine::auto::variable(graph, &name, &decl)?;
        let threads: Vec<Option<u64>> = if variable.pool {
            vec![Some(1 << 16), Some(1 << 17), Some(1 << 19), Some(1 << 20)]
        } else {
            vec![decl.threads]
        };
        let states: &[StateStorage] = if variable.state {
            &[StateStorage::SoA, StateStorage::AoS]
        } else {
            &[StateStorage::SoA]
        };
        for workgroup_size in [32, 64, 128, 256] {
            for &t in &threads {
                for &state in states {
                    let variant = LayoutDecl {
                        workgroup_size,
                        threads: t,
                        state,
                        ..decl.clone()
                    };
                    let label = format!("{base} ({})", options_of(&variant));
                    if trials.iter().any(|tr| tr.name == label) {
                        continue;
                    }
                    run(label, variant, &mut trials);
                }
            }
        }
    }
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    // The fastest once more with wgpu's loop guards the other way (LayoutDecl::loop_guards).
    let (name, decl) = (trials[0].name.clone(), trials[0].decl.clone());
    let flipped = LayoutDecl {
        loop_guards: !decl.loop_guards,
        ..decl
    };
    run(
        format!("{} ({})", base_name(&name), options_of(&flipped)),
        flipped,
        &mut trials,
    );
    trials.sort_by(|a, b| b.score().total_cmp(&a.score()));
    Ok(trials)
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
