//! Import circles: cycles in the graph of dependencies between sibling modules.

use super::edges::Dependency;
use super::tree::Crate;
use petgraph::algo::tarjan_scc;
use petgraph::graphmap::DiGraphMap;
use std::collections::BTreeMap;

/// Circles listed per strongly connected set before the rest are summed up.
const MAX_CIRCLES: usize = 50;

/// One circle: sibling modules each of which depends on the next, the last on the first.
pub struct Circle {
    /// `crate: a -> b -> a`, module paths from the crate root.
    pub name: String,
    /// For each step, `a -> b: file names path`.
    pub evidence: Vec<String>,
}

/// The sibling pair a dependency between two modules is charged to: the children of their
/// lowest common ancestor on the way to each, or None when one contains the other.
fn siblings(krate: &Crate, from: usize, to: usize) -> Option<(usize, usize)> {
    let (a, b) = (krate.ancestry(from), krate.ancestry(to));
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    Some((*a.get(common)?, *b.get(common)?))
}

/// The circles of `krate` given its dependencies, sorted by name.
pub fn circles(krate: &Crate, dependencies: &[Dependency]) -> Vec<Circle> {
    let mut graph = DiGraphMap::<usize, ()>::new();
    let mut why: BTreeMap<(usize, usize), String> = BTreeMap::new();
    for d in dependencies {
        if let Some(pair) = siblings(krate, d.from, d.to) {
            graph.add_edge(pair.0, pair.1, ());
            why.entry(pair).or_insert_with(|| {
                let file = krate.modules[d.from].file.display();
                format!(
                    "{} -> {}: {file} names {}",
                    krate.display(pair.0),
                    krate.display(pair.1),
                    d.via
                )
            });
        }
    }
    let mut out = Vec::new();
    for mut set in tarjan_scc(&graph).into_iter().filter(|s| s.len() > 1) {
        set.sort_by_key(|&m| krate.display(m));
        let cycles = elementary_cycles(&graph, &set);
        if cycles.len() > MAX_CIRCLES {
            let names: Vec<String> = set.iter().map(|&m| krate.display(m)).collect();
            out.push(Circle {
                name: format!("{}: {} circles among {}", krate.name, cycles.len(), names.join(", ")),
                evidence: Vec::new(),
            });
            continue;
        }
        for cycle in cycles {
            let mut names: Vec<String> = cycle.iter().map(|&m| krate.display(m)).collect();
            names.push(names[0].clone());
            let evidence = cycle
                .iter()
                .zip(cycle.iter().cycle().skip(1))
                .map(|(&a, &b)| why[&(a, b)].clone())
                .collect();
            out.push(Circle {
                name: format!("{}: {}", krate.name, names.join(" -> ")),
                evidence,
            });
        }
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

/// Every elementary cycle within the strongly connected `set` (sorted), each starting at its
/// first module in `set`'s order; stops past [`MAX_CIRCLES`].
fn elementary_cycles(graph: &DiGraphMap<usize, ()>, set: &[usize]) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    for (i, &start) in set.iter().enumerate() {
        let allowed = &set[i..];
        let mut path = vec![start];
        extend(graph, allowed, &mut path, &mut out);
    }
    out
}

/// The cycles that continue `path` within `allowed` back to its start.
fn extend(graph: &DiGraphMap<usize, ()>, allowed: &[usize], path: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
    let last = path[path.len() - 1];
    for next in graph.neighbors(last) {
        if out.len() > MAX_CIRCLES {
            return;
        }
        if next == path[0] {
            out.push(path.clone());
        } else if allowed.contains(&next) && !path.contains(&next) {
            path.push(next);
            extend(graph, allowed, path, out);
            path.pop();
        }
    }
}
