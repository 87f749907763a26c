//! Specialisation: the constants' values, then culling that knows them. A pass or operator
//! whose `enabled` condition is 0 leaves the graph, and with it every pass of a chain that
//! starts with it and every chain that nothing live feeds; then whatever no output depends
//! on leaves too. What remains is the live graph that plans, kernels and memory are made of.
//! Loading ends here too: [`Graph::load`] gives the declared graph's view of its default
//! constants.

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::graph::{ChainEntry, Culled, FrameStep, Graph};
use crate::ids::{ChainId, OpId};
use crate::ir::ConstValue;
use crate::load::Entry;
use crate::vfs::Vfs;
use petgraph::visit::{Bfs, Reversed};
use std::collections::{BTreeMap, BTreeSet};

/// A node of the declared graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Node {
    Pass(usize),
    Op(usize),
}

impl Graph {
    /// Loads the graph at virtual path `file` from `vfs`.
    pub fn load(vfs: &Vfs, file: &str) -> Result<Graph> {
        let text = vfs.read(file)?;
        Self::from_text(vfs, file, &text)
    }

    /// Loads a graph from its text (`file` names it in errors). The live view is that of the
    /// default constants; [`Graph::specialize`] gives the view of others.
    pub fn from_text(vfs: &Vfs, file: &str, text: &str) -> Result<Graph> {
        Graph::declare(vfs, file, text)?.specialize_view(&BTreeMap::new(), &BTreeSet::new(), false)
    }

    /// The live view of the graph with `constants` (the graph's defaults overridden and
    /// extended), reads and writes derived without host flags; every `enabled` condition must
    /// evaluate.
    pub fn specialize(&self, constants: &BTreeMap<String, ConstValue>) -> Result<Graph> {
        self.specialize_for(constants, &BTreeSet::new())
    }

    /// The live view of the graph with `constants`, the reads and writes that passes leave out
    /// derived from the WGSL preprocessed with `flags` (and the true `Bool` constants).
    pub fn specialize_for(&self, constants: &BTreeMap<String, ConstValue>, flags: &BTreeSet<String>) -> Result<Graph> {
        self.clone().specialize_view(constants, flags, true)
    }

    /// Recomputes the live view. When not `strict`, a condition naming a constant that is
    /// not known yet (a host constant such as `PATHS`) keeps its pass.
    fn specialize_view(
        mut self,
        given: &BTreeMap<String, ConstValue>,
        flags: &BTreeSet<String>,
        strict: bool,
    ) -> Result<Graph> {
        self.constants = self.declared.constants.clone();
        for (name, v) in given {
            if let Some(default) = self.declared.constants.get(name)
                && default.wgsl_type() != v.wgsl_type()
            {
                return Err(self.error_at_decl(
                    name,
                    format!(
                        "constant '{name}' is {} in the graph but was given as {}",
                        default.wgsl_type(),
                        v.wgsl_type()
                    ),
                ));
            }
            if self.declared.derived.contains_key(name) && !matches!(v, ConstValue::U32(_)) {
                return Err(self.error_at_decl(
                    name,
                    format!("constant '{name}' is a derived u32 but was given as {}", v.wgsl_type()),
                ));
            }
            self.constants.insert(name.clone(), *v);
        }
        self.derive_constants(given, strict)?;
        let vars: BTreeMap<String, f64> = self.constants.iter().map(|(k, v)| (k.clone(), v.as_f64())).collect();
        self.check_constants(&vars)?;
        // The hooks the graph replaces, against their defaults: their own errors always, a
        // compile that fails otherwise only where every constant is known.
        match crate::derive::check_hooks(&self, flags) {
            Err(e @ Error::Invalid { .. }) => return Err(e),
            Err(e) if strict => return Err(e),
            _ => {}
        }
        // What the passes that leave out their reads or writes use, before culling needs it.
        // The default constants' view may not compile yet (a host constant of another type
        // than a placeholder's); it then culls nothing that depends on what passes use.
        let derived = match self.derive_access(flags) {
            Ok(()) => true,
            Err(_) if !strict => false,
            Err(e) => return Err(e),
        };
        // The whole declared structure, to cull on.
        self.passes = self.declared.passes.clone();
        self.ops = self.live_ops(&self.declared.ops);
        self.chains = self.build_chains()?;
        let mut culled: BTreeMap<Node, String> = self.disabled(&vars, strict)?;
        self.cull_orphans(&mut culled);
        self.keep_live(&culled);
        if derived {
            self.cull_unread(&mut culled)?;
            self.keep_live(&culled);
        }
        self.culled = self
            .declared
            .entries
            .iter()
            .filter_map(|e| {
                let node = match *e {
                    Entry::Pass(i) => Node::Pass(i),
                    Entry::Op(i) => Node::Op(i),
                };
                culled.get(&node).map(|reason| Culled {
                    name: self.node_name(node).to_string(),
                    reason: reason.clone(),
                })
            })
            .collect();
        self.check_live(derived)?;
        Ok(self)
    }

    /// The graph's `checks` whose constants are all known: a condition that is 0 is an error
    /// at its declaration, with the values of the constants it names.
    fn check_constants(&self, vars: &BTreeMap<String, f64>) -> Result<()> {
        for c in &self.declared.checks {
            let Ok(expr) = Expr::parse(&c.condition) else { continue };
            let mut names = expr.names();
            names.sort();
            names.dedup();
            if names.iter().any(|n| !vars.contains_key(n)) {
                continue;
            }
            if expr.eval(vars).is_ok_and(|v| v == 0.0) {
                let values: Vec<String> = names.iter().map(|n| format!("{n} = {}", self.constants[n])).collect();
                return Err(self.declared.sources.at_key(
                    &c.file,
                    &c.condition,
                    format!("'{}' does not hold ({}): {}", c.condition, values.join(", "), c.message),
                ));
            }
        }
        Ok(())
    }

    /// Adds the derived constants the host did not give, each a `u32` count evaluated over
    /// the constants (derived ones may use each other, in any order). When not `strict`, one
    /// naming a constant not known yet is left out.
    fn derive_constants(&mut self, given: &BTreeMap<String, ConstValue>, strict: bool) -> Result<()> {
        let mut pending: Vec<&String> = self
            .declared
            .derived
            .keys()
            .filter(|n| !given.contains_key(*n))
            .collect();
        while !pending.is_empty() {
            let vars: BTreeMap<String, f64> = self.constants.iter().map(|(k, v)| (k.clone(), v.as_f64())).collect();
            let before = pending.len();
            let mut failure = None;
            pending.retain(|name| {
                let text = &self.declared.derived[*name];
                let value = Expr::parse(text).and_then(|e| e.count(&vars));
                match value.and_then(|v| u32::try_from(v).map_err(|_| format!("{v} does not fit a u32"))) {
                    Ok(v) => {
                        self.constants.insert((*name).clone(), ConstValue::U32(v));
                        false
                    }
                    Err(e) => {
                        failure.get_or_insert(((*name).clone(), e));
                        true
                    }
                }
            });
            if pending.len() == before {
                let (name, e) = failure.expect("a pending constant failed");
                if !strict {
                    return Ok(());
                }
                return Err(self.error_at_decl(&name, format!("derived constant '{name}': {e}")));
            }
        }
        Ok(())
    }

    fn node_name(&self, n: Node) -> &str {
        match n {
            Node::Pass(i) => &self.declared.passes[i].decl.name,
            Node::Op(i) => &self.declared.ops[i].name,
        }
    }

    /// Nodes whose `enabled` condition is 0, with the reason.
    fn disabled(&self, vars: &BTreeMap<String, f64>, strict: bool) -> Result<BTreeMap<Node, String>> {
        let mut out = BTreeMap::new();
        let conditions = self
            .declared
            .passes
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                p.decl
                    .enabled
                    .as_ref()
                    .map(|e| (Node::Pass(i), e.clone(), p.origin.clone()))
            })
            .chain(
                self.declared
                    .ops
                    .iter()
                    .enumerate()
                    .filter_map(|(i, o)| o.enabled.as_ref().map(|e| (Node::Op(i), e.clone(), o.origin.clone()))),
            );
        for (node, text, origin) in conditions {
            let expr = Expr::parse(&text).map_err(|e| self.declared.sources.at_name(&origin, &text, e))?;
            let known = expr.names().iter().all(|n| vars.contains_key(n));
            if !known && !strict {
                continue;
            }
            let value = expr.eval(vars).map_err(|e| {
                self.declared
                    .sources
                    .at_name(&origin, &text, format!("'{}': enabled: {e}", self.node_name(node)))
            })?;
            if value == 0.0 {
                let values: Vec<String> = expr
                    .names()
                    .iter()
                    .map(|n| {
                        format!(
                            "{n} = {}",
                            self.constants.get(n).map_or("?".into(), |v| v.wgsl_literal())
                        )
                    })
                    .collect();
                out.insert(node, format!("disabled: `{text}` is 0 with {}", values.join(", ")));
            }
        }
        Ok(out)
    }

    /// Adds the passes of chains whose entry is culled, and the chains nothing live feeds.
    fn cull_orphans(&self, culled: &mut BTreeMap<Node, String>) {
        loop {
            let before = culled.len();
            for chain in &self.chains {
                let entry = chain.passes[0].0;
                let reason = if culled.contains_key(&Node::Pass(entry)) {
                    Some(format!(
                        "its chain begins at '{}', which is culled",
                        self.declared.passes[entry].decl.name
                    ))
                } else if let ChainEntry::Stream(s) = chain.entry {
                    let producers: Vec<usize> = (0..self.declared.passes.len())
                        .filter(|&p| self.declared.passes[p].emits.contains(&s))
                        .collect();
                    let s = &self.streams[s].name;
                    producers
                        .iter()
                        .all(|p| culled.contains_key(&Node::Pass(*p)))
                        .then(|| format!("every pass emitting into stream '{s}' is culled"))
                } else {
                    None
                };
                if let Some(reason) = reason {
                    for &p in &chain.passes {
                        culled.entry(Node::Pass(p.0)).or_insert_with(|| reason.clone());
                    }
                }
            }
            if culled.len() == before {
                return;
            }
        }
    }

    /// Makes the live view the declared graph minus `culled`: passes, operators, chains,
    /// phases, dead streams and the frame's steps.
    fn keep_live(&mut self, culled: &BTreeMap<Node, String>) {
        let d = &self.declared;
        let live_pass: Vec<usize> = (0..d.passes.len())
            .filter(|i| !culled.contains_key(&Node::Pass(*i)))
            .collect();
        let live_op: Vec<usize> = (0..d.ops.len())
            .filter(|i| !culled.contains_key(&Node::Op(*i)))
            .collect();
        self.passes = live_pass.iter().map(|&i| d.passes[i].clone()).collect();
        self.ops = self.live_ops(live_op.iter().map(|&i| &d.ops[i]));
        self.chains = self.build_chains().expect("a subset of valid chains is valid");
        self.phases = self.build_phases().expect("a subset of valid phases is valid");
        let live_names: BTreeSet<&str> = self.passes.iter().map(|p| p.decl.name.as_str()).collect();
        self.dead_streams = self
            .stream_ids()
            .filter(|&s| !live_names.contains(self.streams[s].decl.to.as_str()))
            .collect();
        let mut steps = Vec::new();
        for e in &self.declared.entries {
            match *e {
                Entry::Pass(i) => {
                    if let Some(p) = live_pass.iter().position(|&x| x == i)
                        && let Some(c) = self.chains.iter().position(|c| c.passes[0].0 == p)
                        && matches!(self.chains[c].entry, ChainEntry::Start(_))
                    {
                        steps.push(FrameStep::Phase(self.phase_of_chain(ChainId(c))));
                    }
                }
                Entry::Op(i) => {
                    if let Some(o) = live_op.iter().position(|&x| x == i) {
                        steps.push(FrameStep::Op(OpId(o)));
                    }
                }
            }
        }
        self.steps = steps;
    }

    /// Adds every live node no output depends on (when the graph names outputs).
    fn cull_unread(&self, culled: &mut BTreeMap<Node, String>) -> Result<()> {
        if self.outputs.is_empty() {
            return Ok(());
        }
        let (dg, nodes) = self.dependency_graph();
        let rev = Reversed(&dg);
        let mut reached = BTreeSet::new();
        for o in &self.outputs {
            let mut bfs = Bfs::new(rev, nodes[&format!("resource:{o}")]);
            while let Some(n) = bfs.next(rev) {
                reached.insert(n);
            }
        }
        let reason = format!("no output ({}) depends on what it produces", self.outputs.join(", "));
        for (i, p) in self.declared.passes.iter().enumerate() {
            if let Some(n) = nodes.get(&format!("pass:{}", p.decl.name))
                && !reached.contains(n)
            {
                culled.entry(Node::Pass(i)).or_insert_with(|| reason.clone());
            }
        }
        for (i, o) in self.declared.ops.iter().enumerate() {
            if let Some(n) = nodes.get(&format!("op:{}", o.name))
                && !reached.contains(n)
            {
                culled.entry(Node::Op(i)).or_insert_with(|| reason.clone());
            }
        }
        Ok(())
    }

    /// An error, not a black image: a graph with nothing left, or an output nothing writes
    /// (when what the passes write is known).
    fn check_live(&self, writes_known: bool) -> Result<()> {
        let why = |names: &mut dyn Iterator<Item = &str>| -> String {
            let reasons: Vec<String> = names
                .filter_map(|n| self.culled.iter().find(|c| c.name == n))
                .map(|c| format!("'{}' {}", c.name, c.reason))
                .collect();
            if reasons.is_empty() {
                String::new()
            } else {
                format!(" ({})", reasons.join("; "))
            }
        };
        if self.passes.is_empty() && self.ops.is_empty() {
            let mut all = self.culled.iter().map(|c| c.name.as_str());
            return Err(self.error_at(
                &self.name,
                format!("every pass of graph '{}' is culled{}", self.name, why(&mut all)),
            ));
        }
        for o in self.outputs.iter().filter(|_| writes_known) {
            let id = self.resource_id(o);
            let written = self.passes.iter().any(|p| p.decl.writes.contains(o))
                || self
                    .ops
                    .iter()
                    .any(|op| op.writes().into_iter().any(|&r| Some(r) == id));
            if !written {
                let mut writers = self
                    .declared
                    .passes
                    .iter()
                    .filter(|p| p.decl.writes.contains(o))
                    .map(|p| p.decl.name.as_str())
                    .chain(
                        self.declared
                            .ops
                            .iter()
                            .filter(|op| op.writes().contains(&o))
                            .map(|op| op.name.as_str()),
                    );
                let file = self.declared.sources.declaring(&self.file, o);
                return Err(crate::error::Error::Invalid {
                    at: crate::error::Location::of_name_after(file, self.declared.sources.text(file), "outputs:", o),
                    message: format!("output '{o}' has no live writer{}", why(&mut writers)),
                });
            }
        }
        Ok(())
    }
}
