//! An outline of a graph: its frame as the loops an estimator's paper would write, each step
//! the WGSL function and file that does it and the graph's own resources it reads and writes
//! (the host's, such as scene data, left out), before any layout decides kernels.

use crate::graph::{Chain, ChainEntry, FrameStep, Graph};
use crate::ids::ResourceId;
use crate::ir::{Role, Scope};
use std::fmt::Write;

/// The outline of `graph` (specialised: passes a constant switches off are listed at the end).
pub fn outline(graph: &Graph) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "graph '{}': {}", graph.name, graph.description);
    let _ = writeln!(
        out,
        "each pass: its WGSL function and file, and what it reads (<) and writes (>) of the graph's own resources\n\neach frame:"
    );
    for (s, step) in graph.steps.iter().enumerate() {
        match *step {
            FrameStep::Phase(ph) => {
                for (i, &c) in graph.phases[ph].chains.iter().enumerate() {
                    let lead = if i == 0 { format!("{}.", s + 1) } else { String::new() };
                    chain(graph, &graph.chains[c], &lead, &mut out);
                }
            }
            FrameStep::Op(o) => {
                let op = &graph.ops[o];
                let _ = writeln!(
                    out,
                    "{:>3} {} '{}'{}",
                    format!("{}.", s + 1),
                    op.describe(),
                    op.name,
                    access(graph, op.reads().into_iter(), op.writes().into_iter())
                );
            }
        }
    }
    if !graph.culled.is_empty() {
        let _ = writeln!(out, "\nleft out:");
        for c in &graph.culled {
            let _ = writeln!(out, "  {}: {}", c.name, c.reason);
        }
    }
    out
}

/// One chain: how its items come, its steps, and its loop.
fn chain(graph: &Graph, chain: &Chain, lead: &str, out: &mut String) {
    let first = &graph.passes[chain.passes[0]].decl;
    let head = match (&chain.entry, &first.role) {
        (ChainEntry::Start(_), Role::Start { over, counted }) => {
            let counted = counted
                .as_ref()
                .map_or(String::new(), |c| format!(" (as many as '{c}' counts)"));
            format!("for each of {over} {}{counted}:", chain.item)
        }
        (ChainEntry::Stream(stream), _) => {
            format!(
                "for each {} emitted into '{}':",
                chain.item, graph.streams[*stream].name
            )
        }
        (ChainEntry::Start(_), _) => format!("for each {}:", chain.item),
    };
    let _ = writeln!(out, "{lead:>3} {head}");
    for (i, &p) in chain.passes.iter().enumerate() {
        if chain.loop_start == Some(i) {
            let _ = writeln!(out, "      repeat while the item goes on:");
        }
        let depth = if chain.loop_start.is_some_and(|l| i >= l) { 2 } else { 1 };
        pass(graph, p, depth, out);
    }
}

/// One pass at `depth` levels inside its chain.
fn pass(graph: &Graph, p: crate::ids::PassId, depth: usize, out: &mut String) {
    let pass = &graph.passes[p];
    let d = &pass.decl;
    let emits = if d.emits.is_empty() {
        String::new()
    } else {
        format!("  emits into {}", d.emits.join(", "))
    };
    let indent = "  ".repeat(depth + 2);
    let _ = writeln!(
        out,
        "{indent}{:<24} fn {} ({}){}{emits}",
        d.name,
        pass.function(),
        d.source,
        access(graph, pass.reads.iter(), pass.writes.iter())
    );
}

/// What a step reads and writes of the graph's own resources, as " < a, b > c".
fn access<'a>(
    graph: &Graph,
    reads: impl Iterator<Item = &'a ResourceId>,
    writes: impl Iterator<Item = &'a ResourceId>,
) -> String {
    let own = |list: &mut dyn Iterator<Item = &'a ResourceId>| -> Vec<&str> {
        list.map(|&r| &graph.resources[r])
            .filter(|r| r.decl.scope != Scope::External)
            .map(|r| r.name.as_str())
            .collect()
    };
    let (r, w) = (own(&mut { reads }), own(&mut { writes }));
    let mut s = String::new();
    if !r.is_empty() {
        let _ = write!(s, "  < {}", r.join(", "));
    }
    if !w.is_empty() {
        let _ = write!(s, "  > {}", w.join(", "));
    }
    s
}
