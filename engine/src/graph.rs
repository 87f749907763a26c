//! Loading and validating a frame graph: catalogs, names, streams, item chains, phases and
//! culling. Every error names the file and position of the offending name.

use crate::error::{Error, Location, Result};
use crate::expr::Expr;
use crate::ir::{
    CatalogFile, ConstValue, GraphFile, LayoutDecl, MeasuredDecl, PassDecl, PassEntry, PerCall, ResourceDecl, Role,
    StreamDecl,
};
use crate::vfs::Vfs;
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::{Bfs, Reversed};
use std::collections::{BTreeMap, BTreeSet};

/// A pass of a loaded graph, with the file it was declared in.
#[derive(Debug, Clone)]
pub struct Pass {
    /// The declaration.
    pub decl: PassDecl,
    /// The file (virtual path) that declares it: a catalog or the graph.
    pub origin: String,
}

impl Pass {
    /// The WGSL function implementing the pass.
    pub fn function(&self) -> &str {
        self.decl.function.as_deref().unwrap_or(&self.decl.name)
    }
}

/// How a chain receives its items.
#[derive(Debug, Clone, PartialEq)]
pub enum ChainEntry {
    /// Its first pass is a start pass creating `over` items.
    Start(Expr),
    /// Its first pass consumes the named stream.
    Stream(String),
}

/// An item chain: the passes one item runs through, in order. Steps come first; a group of
/// loop passes, if any, ends the chain.
#[derive(Debug, Clone)]
pub struct Chain {
    /// The WGSL struct of the item.
    pub item: String,
    /// Indices into [`Graph::passes`], entry first.
    pub passes: Vec<usize>,
    /// How items enter the chain.
    pub entry: ChainEntry,
    /// Position in `passes` where the loop group begins, if the chain has one.
    pub loop_start: Option<usize>,
}

/// A phase: one start chain and the stream-fed chains it reaches. Phases are separated by
/// global barriers and run in the order of their start passes.
#[derive(Debug, Clone)]
pub struct Phase {
    /// The chains of the phase, the start chain first.
    pub chains: Vec<usize>,
}

/// A loaded, validated frame graph.
#[derive(Debug, Clone)]
pub struct Graph {
    /// The graph's name.
    pub name: String,
    /// What it computes.
    pub description: String,
    /// The graph file (virtual path) and its text, for error locations.
    pub file: String,
    text: String,
    /// WGSL library files.
    pub library: Vec<String>,
    /// All live passes, catalog passes resolved.
    pub passes: Vec<Pass>,
    /// Resources by name.
    pub resources: BTreeMap<String, ResourceDecl>,
    /// Streams by name.
    pub streams: BTreeMap<String, StreamDecl>,
    /// Counter names.
    pub counters: Vec<String>,
    /// Constants with default values.
    pub constants: BTreeMap<String, ConstValue>,
    /// Resources read by the host.
    pub outputs: Vec<String>,
    /// Constants the host measures before rendering.
    pub measured: BTreeMap<String, MeasuredDecl>,
    /// Layouts by name.
    pub layouts: BTreeMap<String, LayoutDecl>,
    /// The default layout.
    pub default_layout: String,
    /// Item chains.
    pub chains: Vec<Chain>,
    /// Phases in execution order.
    pub phases: Vec<Phase>,
    /// Passes removed because nothing reads what they produce.
    pub culled: Vec<Pass>,
    /// Streams whose consumer was culled (emits into them do nothing).
    pub dead_streams: Vec<String>,
    /// The file system the graph's sources come from.
    pub vfs: Vfs,
}

/// Parses RON text of `file` into `T`, with the parser's position on error.
pub fn parse_ron<T: serde::de::DeserializeOwned>(file: &str, text: &str) -> Result<T> {
    ron::Options::default()
        .with_default_extension(
            ron::extensions::Extensions::IMPLICIT_SOME | ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES,
        )
        .from_str(text)
        .map_err(|e| Error::Parse {
            at: Location {
                file: file.to_string(),
                line: e.span.start.line,
                column: e.span.start.col,
            },
            message: e.code.to_string(),
        })
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

impl Graph {
    /// Loads the graph at virtual path `file` from `vfs`.
    pub fn load(vfs: &Vfs, file: &str) -> Result<Graph> {
        let text = vfs.read(file)?;
        Self::from_text(vfs, file, &text)
    }

    /// Loads a graph from its text (`file` names it in errors).
    pub fn from_text(vfs: &Vfs, file: &str, text: &str) -> Result<Graph> {
        let g: GraphFile = parse_ron(file, text)?;
        let err = |name: &str, message: String| Error::invalid_at_name(file, text, name, message);
        let err_key = |name: &str, message: String| Error::invalid_at_key(file, text, name, message);

        // Catalog passes.
        let mut catalog: BTreeMap<String, Pass> = BTreeMap::new();
        for cat in &g.catalogs {
            let cat_text = vfs
                .read(cat)
                .map_err(|e| err(cat, format!("cannot read pass catalog: {e}")))?;
            let parsed: CatalogFile = parse_ron(cat, &cat_text)?;
            for decl in parsed.passes {
                catalog.insert(
                    decl.name.clone(),
                    Pass {
                        decl,
                        origin: cat.clone(),
                    },
                );
            }
        }
        let mut passes: Vec<Pass> = Vec::new();
        for entry in &g.passes {
            let pass = match entry {
                PassEntry::Use(name) => catalog.get(name).cloned().ok_or_else(|| {
                    let known: Vec<&str> = catalog.keys().map(|s| s.as_str()).collect();
                    err(
                        name,
                        format!(
                            "unknown pass '{name}' (the catalogs {:?} offer: {})",
                            g.catalogs,
                            known.join(", ")
                        ),
                    )
                })?,
                PassEntry::Pass(decl) => Pass {
                    decl: decl.clone(),
                    origin: file.to_string(),
                },
            };
            if passes.iter().any(|p| p.decl.name == pass.decl.name) {
                return Err(err(&pass.decl.name, format!("pass '{}' appears twice", pass.decl.name)));
            }
            passes.push(pass);
        }

        // Names.
        for name in g
            .resources
            .keys()
            .chain(g.streams.keys())
            .chain(g.counters.iter())
            .chain(g.constants.keys())
        {
            if !is_identifier(name) || name.starts_with("lg_") {
                return Err(err_key(
                    name,
                    format!("'{name}' is not a valid name (a WGSL identifier not starting with 'lg_')"),
                ));
            }
        }
        let pass_text = |p: &Pass| -> String {
            if p.origin == file {
                text.to_string()
            } else {
                vfs.read(&p.origin).unwrap_or_default()
            }
        };
        for p in &passes {
            let d = &p.decl;
            if !is_identifier(p.function()) {
                return Err(err(&d.name, format!("pass name '{}' is not a WGSL identifier", d.name)));
            }
            for r in d.reads.iter().chain(d.writes.iter()) {
                if !g.resources.contains_key(r) {
                    let known: Vec<&str> = g.resources.keys().map(|s| s.as_str()).collect();
                    return Err(Error::invalid_at_name(
                        &p.origin,
                        &pass_text(p),
                        r,
                        format!(
                            "unknown resource '{r}' used by pass '{}' (graph '{}' declares: {})",
                            d.name,
                            g.name,
                            known.join(", ")
                        ),
                    ));
                }
            }
            for s in &d.emits {
                if !g.streams.contains_key(s) {
                    return Err(Error::invalid_at_name(
                        &p.origin,
                        &pass_text(p),
                        s,
                        format!("pass '{}' emits into unknown stream '{s}'", d.name),
                    ));
                }
            }
            if let Role::Start { over } = &d.role {
                Expr::parse(over).map_err(|e| Error::invalid_at_name(&p.origin, &pass_text(p), over, e))?;
            }
        }
        for (name, r) in &g.resources {
            if r.scope == crate::ir::Scope::External && r.count.is_some() {
                return Err(err_key(
                    name,
                    format!(
                        "external resource '{name}' has a count; its data sizes it, so write its WGSL type (e.g. array<{}>)",
                        r.ty
                    ),
                ));
            }
            if let Some(count) = &r.count {
                Expr::parse(count).map_err(|e| err(count, format!("resource '{name}': {e}")))?;
            }
        }
        for o in &g.outputs {
            if !g.resources.contains_key(o) {
                return Err(err(o, format!("output '{o}' is not a resource")));
            }
        }
        for (name, s) in &g.streams {
            let consumer = passes
                .iter()
                .find(|p| p.decl.name == s.to)
                .ok_or_else(|| err(&s.to, format!("stream '{name}' feeds unknown pass '{}'", s.to)))?;
            if consumer.decl.item != s.item {
                return Err(err_key(
                    name,
                    format!(
                        "stream type mismatch: stream '{name}' carries '{}' but its consumer '{}' runs over '{}'",
                        s.item, s.to, consumer.decl.item
                    ),
                ));
            }
            if matches!(consumer.decl.role, Role::Start { .. }) {
                return Err(err(
                    &s.to,
                    format!(
                        "stream '{name}' feeds '{}', a Start pass; streams feed Step or Loop passes",
                        s.to
                    ),
                ));
            }
            match &s.per_call {
                PerCall::Number(0) => {
                    return Err(err_key(name, format!("stream '{name}' has per_call 0")));
                }
                PerCall::Expr(e) => {
                    if let Err(why) = crate::expr::Expr::parse(e) {
                        return Err(err_key(name, format!("stream '{name}': per_call: {why}")));
                    }
                }
                PerCall::Number(_) => {}
            }
        }
        for (name, m) in &g.measured {
            if !matches!(g.constants.get(name), Some(ConstValue::F32(_))) {
                return Err(err_key(
                    name,
                    format!("measured constant '{name}' must be declared as an F32 constant"),
                ));
            }
            for c in [&m.ratio.0, &m.ratio.1] {
                if !g.counters.contains(c) {
                    return Err(err_key(name, format!("measured constant '{name}': no counter '{c}'")));
                }
            }
            for (c, v) in &m.set {
                match g.constants.get(c) {
                    Some(d) if d.wgsl_type() == v.wgsl_type() => {}
                    _ => {
                        return Err(err_key(
                            name,
                            format!("measured constant '{name}': sets '{c}', which is no constant of that type"),
                        ));
                    }
                }
            }
        }
        if !g.layouts.contains_key(&g.default_layout) {
            return Err(err(
                &g.default_layout,
                format!("default layout '{}' is not one of the layouts", g.default_layout),
            ));
        }

        let mut graph = Graph {
            name: g.name.clone(),
            description: g.description.clone(),
            file: file.to_string(),
            text: text.to_string(),
            library: g.library.clone(),
            passes,
            resources: g.resources.clone(),
            streams: g.streams.clone(),
            counters: g.counters.clone(),
            constants: g.constants.clone(),
            outputs: g.outputs.clone(),
            measured: g.measured.clone(),
            layouts: g.layouts.clone(),
            default_layout: g.default_layout.clone(),
            chains: Vec::new(),
            phases: Vec::new(),
            culled: Vec::new(),
            dead_streams: Vec::new(),
            vfs: vfs.clone(),
        };
        graph.cull();
        graph.build_chains()?;
        graph.build_phases()?;
        Ok(graph)
    }

    /// An error located at the first occurrence of `name` in the graph file.
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> Error {
        Error::invalid_at_name(&self.file, &self.text, name, message)
    }

    /// Whether the pass called `name` was culled.
    pub fn is_culled(&self, name: &str) -> bool {
        self.culled.iter().any(|p| p.decl.name == name)
    }

    /// Resources some pass declares it writes, culled passes included (their WGSL is still
    /// part of every module).
    pub fn written_resources(&self) -> BTreeSet<String> {
        self.passes
            .iter()
            .chain(&self.culled)
            .flat_map(|p| p.decl.writes.iter().cloned())
            .collect()
    }

    /// An error located at the first occurrence of `name` within the declaration of
    /// `layout` (or at the layout's declaration).
    pub fn error_in_layout(&self, layout: &str, name: &str, message: impl Into<String>) -> Error {
        Error::Invalid {
            at: crate::error::Location::of_name_under_key(&self.file, &self.text, layout, name),
            message: message.into(),
        }
    }

    /// Index of the pass called `name`.
    pub fn pass_index(&self, name: &str) -> Option<usize> {
        self.passes.iter().position(|p| p.decl.name == name)
    }

    /// The chain containing pass `p`, and its position there.
    pub fn chain_of(&self, p: usize) -> (usize, usize) {
        self.chains
            .iter()
            .enumerate()
            .find_map(|(c, chain)| chain.passes.iter().position(|&q| q == p).map(|pos| (c, pos)))
            .expect("every live pass is in a chain")
    }

    /// The phase containing chain `c`.
    pub fn phase_of_chain(&self, c: usize) -> usize {
        self.phases
            .iter()
            .position(|ph| ph.chains.contains(&c))
            .expect("every chain is in a phase")
    }

    /// The dependency graph: passes and resources as nodes; edges for writes, reads, item flow
    /// along chains and stream emits.
    pub fn dependency_graph(&self) -> (DiGraph<String, String>, BTreeMap<String, NodeIndex>) {
        dependency_graph(&self.passes, &self.resources, &self.streams)
    }

    fn cull(&mut self) {
        if self.outputs.is_empty() {
            return;
        }
        let (dg, nodes) = self.dependency_graph();
        let mut live: BTreeSet<NodeIndex> = BTreeSet::new();
        let rev = Reversed(&dg);
        for o in &self.outputs {
            let mut bfs = Bfs::new(rev, nodes[&format!("resource:{o}")]);
            while let Some(n) = bfs.next(rev) {
                live.insert(n);
            }
        }
        let (keep, dropped): (Vec<Pass>, Vec<Pass>) = self
            .passes
            .drain(..)
            .partition(|p| live.contains(&nodes[&format!("pass:{}", p.decl.name)]));
        self.passes = keep;
        self.culled = dropped;
        self.dead_streams = self
            .streams
            .iter()
            .filter(|(_, s)| self.is_culled(&s.to))
            .map(|(n, _)| n.clone())
            .collect();
    }

    fn build_chains(&mut self) -> Result<()> {
        let stream_into: BTreeMap<&str, &str> = self.streams.iter().map(|(n, s)| (s.to.as_str(), n.as_str())).collect();
        let mut chains: Vec<Chain> = Vec::new();
        for (i, p) in self.passes.iter().enumerate() {
            let d = &p.decl;
            let fed_by = self.streams.iter().filter(|(_, s)| s.to == d.name).count();
            if fed_by > 1 {
                return Err(self.error_at(
                    &d.name,
                    format!("pass '{}' is fed by {fed_by} streams; a chain has one entry", d.name),
                ));
            }
            let new_entry = match &d.role {
                Role::Start { over } => Some(ChainEntry::Start(
                    Expr::parse(over).map_err(|e| self.error_at(over, e))?,
                )),
                _ => stream_into
                    .get(d.name.as_str())
                    .map(|s| ChainEntry::Stream(s.to_string())),
            };
            if let Some(entry) = new_entry {
                let loop_start = (d.role == Role::Loop).then_some(0);
                chains.push(Chain {
                    item: d.item.clone(),
                    passes: vec![i],
                    entry,
                    loop_start,
                });
                continue;
            }
            let chain = chains.iter_mut().rev().find(|c| c.item == d.item).ok_or_else(|| {
                self.error_at(
                    &d.name,
                    format!(
                        "pass '{}' over '{}' follows no start pass or stream consumer over '{}'",
                        d.name, d.item, d.item
                    ),
                )
            })?;
            if let Some(ls) = chain.loop_start {
                if d.role != Role::Loop {
                    let looped = &self.passes[chain.passes[ls]].decl.name;
                    return Err(self.error_at(
                        &d.name,
                        format!("pass '{}' is a Step after the loop pass '{looped}' in the chain of '{}': a loop group ends its chain", d.name, d.item),
                    ));
                }
            } else if d.role == Role::Loop {
                chain.loop_start = Some(chain.passes.len());
            }
            chain.passes.push(i);
        }
        self.chains = chains;
        Ok(())
    }

    fn build_phases(&mut self) -> Result<()> {
        // Chains reached from chain c through streams.
        let consumer_chain = |stream: &str| -> Option<usize> {
            self.chains
                .iter()
                .position(|c| c.entry == ChainEntry::Stream(stream.to_string()))
        };
        let mut owner: BTreeMap<usize, usize> = BTreeMap::new();
        let mut phases: Vec<Phase> = Vec::new();
        for (c, chain) in self.chains.iter().enumerate() {
            if !matches!(chain.entry, ChainEntry::Start(_)) {
                continue;
            }
            let phase = phases.len();
            let mut members = vec![c];
            let mut stack = vec![(c, vec![c])];
            while let Some((cur, path)) = stack.pop() {
                for &p in &self.chains[cur].passes {
                    for s in &self.passes[p].decl.emits {
                        let Some(next) = consumer_chain(s) else {
                            continue;
                        };
                        if path.contains(&next) {
                            return Err(self.error_at(
                                s,
                                format!("stream '{s}' closes a cycle of streams; emits cannot recurse"),
                            ));
                        }
                        if let Some(&other) = owner.get(&next)
                            && other != phase
                        {
                            return Err(self.error_at(
                                s,
                                format!("stream '{s}' is emitted in two phases; a stream belongs to one phase"),
                            ));
                        }
                        owner.insert(next, phase);
                        if !members.contains(&next) {
                            members.push(next);
                        }
                        let mut next_path = path.clone();
                        next_path.push(next);
                        stack.push((next, next_path));
                    }
                }
            }
            phases.push(Phase { chains: members });
        }
        for (c, chain) in self.chains.iter().enumerate() {
            if let ChainEntry::Stream(s) = &chain.entry
                && !phases.iter().any(|ph| ph.chains.contains(&c))
            {
                return Err(self.error_at(s, format!("stream '{s}' is emitted by no pass")));
            }
        }
        self.phases = phases;
        Ok(())
    }

    /// A resource written in phase `a` and read in phase `b`, if any (the reason a barrier
    /// separates them).
    pub fn barrier_resource(&self, a: usize, b: usize) -> Option<String> {
        let phase_passes = |ph: usize| -> Vec<&Pass> {
            self.phases[ph]
                .chains
                .iter()
                .flat_map(|&c| self.chains[c].passes.iter().map(|&p| &self.passes[p]))
                .collect()
        };
        let (pa, pb) = (phase_passes(a), phase_passes(b));
        for x in &pa {
            for y in &pb {
                if let Some(r) = x
                    .decl
                    .writes
                    .iter()
                    .find(|r| y.decl.reads.contains(r) || y.decl.writes.contains(r))
                {
                    return Some(r.clone());
                }
                if let Some(r) = y.decl.writes.iter().find(|r| x.decl.reads.contains(r)) {
                    return Some(r.clone());
                }
            }
        }
        None
    }

    /// Graphviz DOT text of the dependency graph.
    pub fn to_dot(&self) -> String {
        let (dg, _) = self.dependency_graph();
        format!("{}", petgraph::dot::Dot::with_config(&dg, &[]))
    }
}

fn dependency_graph(
    passes: &[Pass],
    resources: &BTreeMap<String, ResourceDecl>,
    streams: &BTreeMap<String, StreamDecl>,
) -> (DiGraph<String, String>, BTreeMap<String, NodeIndex>) {
    let mut dg: DiGraph<String, String> = DiGraph::new();
    let mut nodes = BTreeMap::new();
    for r in resources.keys() {
        nodes.insert(format!("resource:{r}"), dg.add_node(format!("resource:{r}")));
    }
    for p in passes {
        nodes.insert(
            format!("pass:{}", p.decl.name),
            dg.add_node(format!("pass:{}", p.decl.name)),
        );
    }
    let mut last_of_item: BTreeMap<&str, NodeIndex> = BTreeMap::new();
    for p in passes {
        let d = &p.decl;
        let n = nodes[&format!("pass:{}", d.name)];
        for r in &d.writes {
            dg.add_edge(n, nodes[&format!("resource:{r}")], "writes".into());
        }
        for r in &d.reads {
            dg.add_edge(nodes[&format!("resource:{r}")], n, "reads".into());
        }
        for s in &d.emits {
            if let Some(to) = nodes.get(&format!("pass:{}", streams[s].to)) {
                dg.add_edge(n, *to, format!("emits {s}"));
            }
        }
        let starts_chain = matches!(d.role, Role::Start { .. }) || streams.values().any(|s| s.to == d.name);
        if !starts_chain && let Some(prev) = last_of_item.get(d.item.as_str()) {
            dg.add_edge(*prev, n, d.item.clone());
        }
        last_of_item.insert(&d.item, n);
    }
    (dg, nodes)
}
