//! Enumerating every legal layout of a graph: each phase's passes partitioned into kernels in
//! every way, crossed with the loop modes and policies, kept when the planner accepts them
//! and distinct in what they run.

use crate::error::Result;
use crate::graph::Graph;
use crate::ir::{LayoutDecl, LoopMode, Policy};
use crate::plan::Plan;
use std::collections::BTreeSet;

/// Every partition of `items` into non-empty groups (restricted growth strings).
fn partitions<T: Clone>(items: &[T]) -> Vec<Vec<Vec<T>>> {
    let n = items.len();
    let mut out = Vec::new();
    let mut labels = vec![0usize; n];
    loop {
        let groups = labels.iter().copied().max().map_or(0, |m| m + 1);
        let mut parts: Vec<Vec<T>> = vec![Vec::new(); groups];
        for (item, &l) in items.iter().zip(&labels) {
            parts[l].push(item.clone());
        }
        out.push(parts);
        // Next restricted growth string: labels[i] <= 1 + max(labels[..i]).
        let mut i = n;
        loop {
            if i <= 1 {
                return out;
            }
            i -= 1;
            let max_before = labels[..i].iter().copied().max().unwrap_or(0);
            if labels[i] <= max_before {
                labels[i] += 1;
                for l in labels.iter_mut().skip(i + 1) {
                    *l = 0;
                }
                break;
            }
        }
    }
}

/// A short name of a layout: its kernels' passes, then its loop mode and policy where they
/// matter.
pub fn describe(plan: &Plan) -> String {
    let g = &plan.graph;
    let kernels: Vec<String> = plan
        .kernel_ids()
        .map(|k| {
            plan.kernel_passes(k)
                .iter()
                .map(|&p| g.passes[p].decl.name.as_str())
                .collect::<Vec<_>>()
                .join("+")
        })
        .collect();
    let host = plan
        .kernels
        .iter()
        .any(|k| !k.loop_in_kernel && g.chains[k.chain].loop_start.is_some_and(|ls| k.segment.end > ls));
    let regen = plan.kernels.iter().any(|k| k.regenerates);
    let mode = match (host, regen, plan.layout.policy) {
        (_, false, _) if host => "host loop",
        (_, false, _) => "in-kernel loop",
        (false, true, _) => "persistent threads",
        (true, true, Policy::Compaction) => "host loop, compaction",
        (true, true, _) => "host loop, regeneration",
    };
    format!("[{}] {mode}", kernels.join("] ["))
}

/// What a plan runs, independent of names and options: two layouts with the same signature
/// run the same kernels in the same way.
pub fn signature(plan: &Plan) -> String {
    let kernels: Vec<String> = plan
        .kernels
        .iter()
        .map(|k| {
            format!(
                "{}:{:?}:{:?}:{:?}:{}:{}:{:?}:{:?}",
                k.chain, k.segment, k.root, k.fused_chains, k.loop_in_kernel, k.regenerates, k.input, k.output
            )
        })
        .collect();
    kernels.join(";")
}

/// Every legal, distinct layout of `graph`, with `base`'s options (workgroup size, state
/// storage, threads), named by [`describe`].
pub fn legal_layouts(graph: &Graph, base: &LayoutDecl) -> Vec<(String, LayoutDecl)> {
    let phase_groups: Vec<Vec<Vec<Vec<String>>>> = graph
        .phases
        .iter()
        .map(|ph| {
            let names: Vec<String> = ph
                .chains
                .iter()
                .flat_map(|&c| {
                    graph.chains[c]
                        .passes
                        .iter()
                        .map(|&p| graph.passes[p].decl.name.clone())
                })
                .collect();
            partitions(&names)
        })
        .collect();
    let mut combos: Vec<Vec<Vec<String>>> = vec![Vec::new()];
    for groups in &phase_groups {
        combos = combos
            .iter()
            .flat_map(|prefix| {
                groups
                    .iter()
                    .map(move |g| prefix.iter().chain(g.iter()).cloned().collect())
            })
            .collect();
    }
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for kernels in combos {
        for loops in [LoopMode::InKernel, LoopMode::Host] {
            for policy in [Policy::Naive, Policy::Regeneration, Policy::Compaction] {
                let decl = LayoutDecl {
                    kernels: kernels.clone(),
                    loops,
                    policy,
                    ..base.clone()
                };
                let Ok(plan) = Plan::with_decl(graph, "auto", decl.clone()) else {
                    continue;
                };
                if seen.insert(signature(&plan)) {
                    let name = describe(&plan);
                    out.push((
                        name,
                        LayoutDecl {
                            description: "found by --layout auto".into(),
                            ..decl
                        },
                    ));
                }
            }
        }
    }
    out
}

/// Which of a layout's options are worth varying: its thread pool, where a kernel regenerates
/// items, and its state storage, where items are stored between kernels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Variable {
    /// A kernel regenerates items from a pool of threads.
    pub pool: bool,
    /// Items or their streams are stored in buffers between kernels.
    pub state: bool,
}

/// Checks that the layout `decl` (called `name` in errors) plans for `graph` (a layout kept
/// from an earlier run: a cache).
pub fn check(graph: &Graph, name: &str, decl: &LayoutDecl) -> Result<()> {
    variable(graph, name, decl).map(|_| ())
}

/// What of the layout `decl` (called `name` in errors) of `graph` is worth varying; an error
/// where the layout does not plan.
pub fn variable(graph: &Graph, name: &str, decl: &LayoutDecl) -> Result<Variable> {
    let plan = Plan::with_decl(graph, name, decl.clone())?;
    Ok(Variable {
        pool: plan.kernels.iter().any(|k| k.regenerates),
        state: !plan.stored_chains.is_empty() || !plan.boundaries.is_empty() || !plan.queued_streams.is_empty(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_partitions_by_bell_numbers() {
        let sizes: Vec<usize> = (1..=6).map(|n| partitions(&(0..n).collect::<Vec<_>>()).len()).collect();
        assert_eq!(sizes, vec![1, 2, 5, 15, 52, 203]);
    }
}
