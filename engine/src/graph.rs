//! A loaded frame graph: its declarations, and the live view the current constants leave of
//! it (see [`crate::specialize`]): item chains, phases, and the frame's steps (phases and
//! operators in order). Resources and streams are interned to typed ids where the live graph
//! is built ([`Graph::resources`], [`Graph::streams`]); their names serve the edges: errors,
//! reports and the host's lookups ([`Graph::resource_id`]). Every error names the file and
//! position of the offending name.

use crate::error::{Error, Result};
use crate::extend::resolve;
use crate::ids::{ChainId, OpId, PassId, PhaseId, ResourceId, StreamId, indexes};
use crate::ir::{ConstValue, LayoutDecl, MeasuredDecl, ResourceDecl, Role, StreamDecl};
use crate::load::{Declared, Pass, declare};
use crate::operator::{Domain, Operator};
use crate::vfs::Vfs;
use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex};

pub use crate::load::parse_ron;

/// How a chain receives its items.
#[derive(Debug, Clone, PartialEq)]
pub enum ChainEntry {
    /// Its first pass is a start pass creating items over a domain.
    Start(Domain<ResourceId>),
    /// Its first pass consumes the stream.
    Stream(StreamId),
}

/// An item chain: the passes one item runs through, in order. Steps come first; a group of
/// loop passes, if any, ends the chain.
#[derive(Debug, Clone)]
pub struct Chain {
    /// The WGSL struct of the item.
    pub item: String,
    /// Its passes, entry first.
    pub passes: Vec<PassId>,
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
    pub chains: Vec<ChainId>,
}

indexes!(ChainId => Chain);
indexes!(PhaseId => Phase);

/// A resource of the live graph: its name (for errors, reports and the host) and declaration.
#[derive(Debug, Clone)]
pub struct Resource {
    /// Its name.
    pub name: String,
    /// Its declaration.
    pub decl: ResourceDecl,
}

/// A stream of the graph: its name (for errors and reports) and declaration.
#[derive(Debug, Clone)]
pub struct Stream {
    /// Its name.
    pub name: String,
    /// Its declaration.
    pub decl: StreamDecl,
}

indexes!(ResourceId => Resource);
indexes!(StreamId => Stream);

/// Declarations by name interned in name order: the table an id indexes, and each name's id.
fn intern<I, D, T>(
    decls: BTreeMap<String, D>,
    id: fn(usize) -> I,
    item: fn(String, D) -> T,
) -> (Vec<T>, BTreeMap<String, I>) {
    let ids = decls.keys().enumerate().map(|(i, n)| (n.clone(), id(i))).collect();
    (decls.into_iter().map(|(n, d)| item(n, d)).collect(), ids)
}

/// One step of a frame: a phase of passes, or a collective operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameStep {
    /// A phase.
    Phase(PhaseId),
    /// An operator.
    Op(OpId),
}

/// A pass or operator left out of the live graph, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Culled {
    /// Its name.
    pub name: String,
    /// Why it was culled.
    pub reason: String,
}

/// The reads and writes of every declared pass, derived or listed, by the flags (the host's
/// and the true `Bool` constants) they were derived with (the specialise stage): a graph's views
/// (a compile per layout, each specialised anew) derive once per set of flags.
pub(crate) type Derivations = Arc<Mutex<BTreeMap<BTreeSet<String>, Vec<(Vec<String>, Vec<String>)>>>>;

/// A loaded, validated frame graph with the live view of its constants.
#[derive(Debug, Clone)]
pub struct Graph {
    /// The graph's name.
    pub name: String,
    /// What it computes.
    pub description: String,
    /// The graph file (virtual path).
    pub file: String,
    /// Everything declared, culled or not.
    pub declared: Declared,
    /// WGSL library files.
    pub library: Vec<String>,
    /// Live passes.
    pub passes: Vec<Pass>,
    /// Live operators.
    pub ops: Vec<Operator<ResourceId>>,
    /// The live graph's resources, in name order, by id.
    pub resources: Vec<Resource>,
    /// The id of each resource's name: for the edges (parsing, errors, the host's lookups,
    /// [`Graph::resource_id`]).
    pub(crate) resource_by_name: BTreeMap<String, ResourceId>,
    /// Streams, in name order, by id.
    pub streams: Vec<Stream>,
    /// The id of each stream's name ([`Graph::stream_id`]).
    pub(crate) stream_by_name: BTreeMap<String, StreamId>,
    /// Counter names.
    pub counters: Vec<String>,
    /// Constants: the graph's defaults, overridden and extended by the specialisation.
    pub constants: BTreeMap<String, ConstValue>,
    /// Per-frame parameters with their defaults.
    pub parameters: BTreeMap<String, ConstValue>,
    /// Resources read by the host.
    pub outputs: Vec<String>,
    /// Constants the host measures before rendering.
    pub measured: BTreeMap<String, MeasuredDecl>,
    /// Layouts by name.
    pub layouts: BTreeMap<String, LayoutDecl>,
    /// The default layout.
    pub default_layout: String,
    /// Item chains of the live passes.
    pub chains: Vec<Chain>,
    /// Phases in execution order.
    pub phases: Vec<Phase>,
    /// The frame: phases and operators in order.
    pub steps: Vec<FrameStep>,
    /// Passes and operators left out, with the reason.
    pub culled: Vec<Culled>,
    /// Streams whose consumer was culled (emits into them do nothing).
    pub dead_streams: Vec<StreamId>,
    /// The file system the graph's sources come from.
    pub vfs: Vfs,
    /// The reads and writes derived for each set of flags, shared by the graph's views.
    pub(crate) derivations: Derivations,
}

impl Graph {
    /// A graph from its text (`file` names it in errors), its chains and phases built on every
    /// declared pass: the structure is checked whatever the constants cull. [`Graph::load`]
    /// gives its live view of the default constants.
    pub(crate) fn declare(vfs: &Vfs, file: &str, text: &str) -> Result<Graph> {
        let declared = declare(vfs, file, resolve(vfs, file, text)?)?;
        crate::hooks::check(&declared, vfs, file)?;
        crate::item_fields::check(&declared, vfs, file)?;
        let g = &declared.file;
        let g_streams = g.streams.clone();
        let mut graph = Graph {
            name: g.name.clone(),
            description: g.description.clone(),
            file: file.to_string(),
            library: declared.library.clone(),
            passes: Vec::new(),
            ops: Vec::new(),
            resources: Vec::new(),
            resource_by_name: BTreeMap::new(),
            streams: Vec::new(),
            stream_by_name: BTreeMap::new(),
            counters: declared.counters.clone(),
            constants: declared.constants.clone(),
            parameters: g.parameters.clone(),
            outputs: g.outputs.clone(),
            measured: g.measured.clone(),
            layouts: g.layouts.iter().map(|(n, l)| (n.clone(), l.decl())).collect(),
            default_layout: g.default_layout.clone(),
            chains: Vec::new(),
            phases: Vec::new(),
            steps: Vec::new(),
            culled: Vec::new(),
            dead_streams: Vec::new(),
            vfs: vfs.clone(),
            derivations: Default::default(),
            declared,
        };
        (graph.streams, graph.stream_by_name) = intern(g_streams, StreamId, |name, decl| Stream { name, decl });
        for p in &mut graph.declared.passes {
            p.emits = p.decl.emits.iter().map(|s| graph.stream_by_name[s]).collect();
        }
        graph.intern_resources(graph.declared.resources.clone());
        graph.passes = graph.declared.passes.clone();
        graph.ops = graph.live_ops(&graph.declared.ops);
        graph.chains = graph.build_chains()?;
        graph.phases = graph.build_phases()?;
        Ok(graph)
    }

    /// Interns `resources` (the live graph's) in name order, and gives every declared pass the
    /// ids of the resources it reads and writes.
    pub(crate) fn intern_resources(&mut self, resources: BTreeMap<String, ResourceDecl>) {
        (self.resources, self.resource_by_name) = intern(resources, ResourceId, |name, decl| Resource { name, decl });
        let ids = |names: &[String]| -> Vec<ResourceId> { names.iter().map(|n| self.resource_by_name[n]).collect() };
        for p in &mut self.declared.passes {
            (p.reads, p.writes) = (ids(&p.decl.reads), ids(&p.decl.writes));
        }
    }

    /// `ops` (declared ones) with their resources named by the live graph's ids.
    pub(crate) fn live_ops<'a>(&self, ops: impl IntoIterator<Item = &'a Operator>) -> Vec<Operator<ResourceId>> {
        ops.into_iter()
            .map(|op| op.map(&|n| self.resource_by_name[n]))
            .collect()
    }

    /// The id of the resource called `name`, if the live graph has it.
    pub fn resource_id(&self, name: &str) -> Option<ResourceId> {
        self.resource_by_name.get(name).copied()
    }

    /// The live resource called `name`.
    pub fn resource(&self, name: &str) -> Option<&Resource> {
        self.resource_id(name).map(|r| &self.resources[r])
    }

    /// The ids of the live resources, in name order.
    pub fn resource_ids(&self) -> impl Iterator<Item = ResourceId> + use<> {
        (0..self.resources.len()).map(ResourceId)
    }

    /// The id of the stream called `name`.
    pub fn stream_id(&self, name: &str) -> Option<StreamId> {
        self.stream_by_name.get(name).copied()
    }

    /// The ids of the streams, in name order.
    pub fn stream_ids(&self) -> impl Iterator<Item = StreamId> + use<> {
        (0..self.streams.len()).map(StreamId)
    }

    /// The layout called `name`; an unknown name is an error that lists the graph's layouts.
    pub fn layout(&self, name: &str) -> Result<&LayoutDecl> {
        self.layouts.get(name).ok_or_else(|| {
            let known: Vec<&str> = self.layouts.keys().map(|s| s.as_str()).collect();
            self.error_at(
                &self.name,
                format!(
                    "unknown layout '{name}' for graph '{}'; available layouts: {}",
                    self.name,
                    known.join(", ")
                ),
            )
        })
    }

    /// An error located at the first occurrence of `name` in the graph file.
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> Error {
        self.declared.sources.at_name(&self.file, name, message)
    }

    /// An error located at the declaration of the resource, counter or constant `name`.
    pub fn error_at_decl(&self, name: &str, message: impl Into<String>) -> Error {
        self.declared.error_at_decl(&self.file, name, message)
    }

    /// An error located at the first occurrence of `name` in the file of pass `p`.
    pub fn error_in_pass(&self, p: &Pass, name: &str, message: impl Into<String>) -> Error {
        self.declared.sources.at_name(&p.origin, name, message)
    }

    /// Whether the pass or operator called `name` was culled.
    pub fn is_culled(&self, name: &str) -> bool {
        self.culled.iter().any(|c| c.name == name)
    }

    /// Resources some declared pass or operator writes, culled ones included (the sources
    /// of culled passes still take part in compiling, so their stores must be legal).
    pub fn written_resources(&self) -> BTreeSet<ResourceId> {
        let mut out: BTreeSet<ResourceId> = self
            .declared
            .passes
            .iter()
            .flat_map(|p| p.writes.iter().copied())
            .collect();
        for op in &self.declared.ops {
            out.extend(op.writes().into_iter().map(|r| self.resource_by_name[r]));
        }
        out
    }

    /// An error located at the first occurrence of `name` within the declaration of
    /// `layout` (or at the layout's declaration).
    pub fn error_in_layout(&self, layout: &str, name: &str, message: impl Into<String>) -> Error {
        let sources = &self.declared.sources;
        let file = sources.declaring(&self.file, layout);
        Error::Invalid {
            at: crate::error::Location::of_name_under_key(file, sources.text(file), layout, name),
            message: message.into(),
        }
    }

    /// The live pass called `name`.
    pub fn pass_index(&self, name: &str) -> Option<PassId> {
        self.passes.iter().position(|p| p.decl.name == name).map(PassId)
    }

    /// The chain containing pass `p`, and its position there.
    pub fn chain_of(&self, p: PassId) -> (ChainId, usize) {
        self.chains
            .iter()
            .enumerate()
            .find_map(|(c, chain)| chain.passes.iter().position(|&q| q == p).map(|pos| (ChainId(c), pos)))
            .expect("every live pass is in a chain")
    }

    /// The phase containing chain `c`.
    pub fn phase_of_chain(&self, c: ChainId) -> PhaseId {
        PhaseId(
            self.phases
                .iter()
                .position(|ph| ph.chains.contains(&c))
                .expect("every chain is in a phase"),
        )
    }

    /// The frame step of phase `ph`.
    pub fn step_of_phase(&self, ph: PhaseId) -> usize {
        self.steps
            .iter()
            .position(|s| *s == FrameStep::Phase(ph))
            .expect("every phase is a step")
    }

    /// The passes of phase `ph`.
    pub fn phase_passes(&self, ph: PhaseId) -> Vec<PassId> {
        self.phases[ph]
            .chains
            .iter()
            .flat_map(|&c| self.chains[c].passes.iter().copied())
            .collect()
    }

    /// The domain of phase `ph`: its start chain's.
    pub fn phase_domain(&self, ph: PhaseId) -> &Domain<ResourceId> {
        match &self.chains[self.phases[ph].chains[0]].entry {
            ChainEntry::Start(d) => d,
            ChainEntry::Stream(_) => unreachable!("phases begin with a start chain"),
        }
    }

    /// Resources the nodes of frame step `s` read or write (counters of GPU-counted domains
    /// included).
    pub fn step_resources(&self, s: usize) -> BTreeSet<ResourceId> {
        let mut out = BTreeSet::new();
        match self.steps[s] {
            FrameStep::Phase(ph) => {
                for p in self.phase_passes(ph) {
                    let p = &self.passes[p];
                    out.extend(p.reads.iter().chain(&p.writes).copied());
                }
                out.extend(self.phase_domain(ph).counted);
            }
            FrameStep::Op(o) => {
                let op = &self.ops[o];
                out.extend(op.reads().into_iter().chain(op.writes()).copied());
            }
        }
        out
    }

    /// A resource written in phase `a` and read in phase `b`, if any (the reason a barrier
    /// separates them).
    pub fn barrier_resource(&self, a: PhaseId, b: PhaseId) -> Option<ResourceId> {
        let (pa, pb) = (self.phase_passes(a), self.phase_passes(b));
        for &x in &pa {
            for &y in &pb {
                let (x, y) = (&self.passes[x], &self.passes[y]);
                if let Some(&r) = x.writes.iter().find(|r| y.reads.contains(r) || y.writes.contains(r)) {
                    return Some(r);
                }
                if let Some(&r) = y.writes.iter().find(|r| x.reads.contains(r)) {
                    return Some(r);
                }
            }
        }
        None
    }

    /// Why phases `a` and `b` cannot share a kernel, in words.
    pub fn barrier_reason(&self, a: PhaseId, b: PhaseId) -> String {
        let (a, b) = (a.min(b), a.max(b));
        let (sa, sb) = (self.step_of_phase(a), self.step_of_phase(b));
        if let Some(r) = self.barrier_resource(a, b) {
            let r = &self.resources[r].name;
            return format!("the later phase needs all of '{r}' from the earlier one (a global barrier)");
        }
        match self.steps[sa..sb].iter().find_map(|s| match s {
            FrameStep::Op(o) => Some(&self.ops[*o].name),
            FrameStep::Phase(_) => None,
        }) {
            Some(op) => format!("operator '{op}' runs between them (a global barrier)"),
            None => "they belong to independent phases".to_string(),
        }
    }

    /// The dependency graph of the live passes and operators: passes, operators and
    /// resources as nodes; edges for writes, reads, item flow along chains and stream emits.
    pub fn dependency_graph(&self) -> (DiGraph<String, String>, BTreeMap<String, NodeIndex>) {
        dependency_graph(self)
    }

    /// Graphviz DOT text of the dependency graph.
    pub fn to_dot(&self) -> String {
        let (dg, _) = self.dependency_graph();
        format!("{}", petgraph::dot::Dot::with_config(&dg, &[]))
    }

    /// The chains of the live passes, in order of their entries.
    pub(crate) fn build_chains(&self) -> Result<Vec<Chain>> {
        let stream_into: BTreeMap<&str, StreamId> = self
            .stream_ids()
            .map(|s| (self.streams[s].decl.to.as_str(), s))
            .collect();
        let mut chains: Vec<Chain> = Vec::new();
        for (i, p) in self.passes.iter().enumerate() {
            let d = &p.decl;
            let fed_by = self.streams.iter().filter(|s| s.decl.to == d.name).count();
            if fed_by > 1 {
                return Err(self.error_at(
                    &d.name,
                    format!("pass '{}' is fed by {fed_by} streams; a chain has one entry", d.name),
                ));
            }
            let new_entry = match &d.role {
                Role::Start { over, counted } => Some(ChainEntry::Start(Domain {
                    over: crate::expr::Expr::parse(over).map_err(|e| self.error_in_pass(p, over, e))?,
                    counted: counted.as_deref().map(|c| self.counter_id(p, c)).transpose()?,
                })),
                _ => stream_into.get(d.name.as_str()).map(|&s| ChainEntry::Stream(s)),
            };
            if let Some(entry) = new_entry {
                let loop_start = (d.role == Role::Loop).then_some(0);
                chains.push(Chain {
                    item: d.item.clone(),
                    passes: vec![PassId(i)],
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
            chain.passes.push(PassId(i));
        }
        Ok(chains)
    }

    /// The id of resource `counter` that start pass `p` is counted by.
    fn counter_id(&self, p: &Pass, counter: &str) -> Result<ResourceId> {
        self.resource_id(counter).ok_or_else(|| {
            let message = format!("'{}' is counted by unknown resource '{counter}'", p.decl.name);
            self.error_in_pass(p, counter, message)
        })
    }

    /// The phases of the chains: each start chain with the chains its streams reach.
    pub(crate) fn build_phases(&self) -> Result<Vec<Phase>> {
        let consumer_chain = |stream: StreamId| -> Option<ChainId> {
            self.chains
                .iter()
                .position(|c| c.entry == ChainEntry::Stream(stream))
                .map(ChainId)
        };
        let mut owner: BTreeMap<ChainId, usize> = BTreeMap::new();
        let mut phases: Vec<Phase> = Vec::new();
        for (c, chain) in self.chains.iter().enumerate() {
            let c = ChainId(c);
            if !matches!(chain.entry, ChainEntry::Start(_)) {
                continue;
            }
            let phase = phases.len();
            let mut members = vec![c];
            let mut stack = vec![(c, vec![c])];
            while let Some((cur, path)) = stack.pop() {
                for &p in &self.chains[cur].passes {
                    for &s in &self.passes[p].emits {
                        let Some(next) = consumer_chain(s) else {
                            continue;
                        };
                        let s = &self.streams[s].name;
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
            if let ChainEntry::Stream(s) = chain.entry
                && !phases.iter().any(|ph| ph.chains.contains(&ChainId(c)))
            {
                let s = &self.streams[s].name;
                return Err(self.error_at(s, format!("stream '{s}' is emitted by no pass")));
            }
        }
        Ok(phases)
    }
}

/// The dependency graph of `g`'s live passes and operators (see [`Graph::dependency_graph`]),
/// its nodes keyed by kind and name.
fn dependency_graph(g: &Graph) -> (DiGraph<String, String>, BTreeMap<String, NodeIndex>) {
    let (passes, chains) = (&g.passes, &g.chains);
    let mut dg: DiGraph<String, String> = DiGraph::new();
    let mut nodes = BTreeMap::new();
    let mut node = |dg: &mut DiGraph<String, String>, key: String| {
        let n = dg.add_node(key.clone());
        nodes.insert(key, n);
    };
    for r in &g.resources {
        node(&mut dg, format!("resource:{}", r.name));
    }
    for p in passes {
        node(&mut dg, format!("pass:{}", p.decl.name));
    }
    for o in &g.ops {
        node(&mut dg, format!("op:{}", o.name));
    }
    let resource = |r: &ResourceId| nodes[&format!("resource:{}", g.resources[*r].name)];
    let reads_writes =
        |dg: &mut DiGraph<String, String>, n: NodeIndex, reads: Vec<&ResourceId>, writes: Vec<&ResourceId>| {
            for r in writes {
                dg.add_edge(n, resource(r), "writes".into());
            }
            for r in reads {
                dg.add_edge(resource(r), n, "reads".into());
            }
        };
    for p in passes {
        let d = &p.decl;
        let n = nodes[&format!("pass:{}", d.name)];
        let mut reads: Vec<&ResourceId> = p.reads.iter().collect();
        if let Role::Start { counted: Some(c), .. } = &d.role {
            reads.push(&g.resource_by_name[c]);
        }
        reads_writes(&mut dg, n, reads, p.writes.iter().collect());
        for &s in &p.emits {
            let s = &g.streams[s];
            if let Some(to) = nodes.get(&format!("pass:{}", s.decl.to)) {
                dg.add_edge(n, *to, format!("emits {}", s.name));
            }
        }
    }
    for o in &g.ops {
        reads_writes(&mut dg, nodes[&format!("op:{}", o.name)], o.reads(), o.writes());
    }
    for chain in chains {
        for pair in chain.passes.windows(2) {
            let (a, b) = (&passes[pair[0].0].decl.name, &passes[pair[1].0].decl.name);
            dg.add_edge(
                nodes[&format!("pass:{a}")],
                nodes[&format!("pass:{b}")],
                chain.item.clone(),
            );
        }
        // A loop pass decides whether the whole group repeats: the group's first pass
        // depends on its last, so a pass that only ends the loop lives with the group.
        if let (Some(ls), Some(last)) = (chain.loop_start, chain.passes.last())
            && chain.passes.len() > ls + 1
        {
            let (first, last) = (&passes[chain.passes[ls].0].decl.name, &passes[last.0].decl.name);
            dg.add_edge(
                nodes[&format!("pass:{last}")],
                nodes[&format!("pass:{first}")],
                format!("{} loop", chain.item),
            );
        }
    }
    (dg, nodes)
}
