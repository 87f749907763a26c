//! Layout planning: turning a graph's fusion groups into kernels, checking that the fusion
//! is legal, and deriving the order kernels run in within each phase.

use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{ChainEntry, Graph};
use crate::ids::{BoundaryId, ChainId, KernelId, PassId, PhaseId, StreamId, indexes};
use crate::ir::{LayoutDecl, LoopMode, Policy, Role};
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;

/// What feeds a kernel its items.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Root {
    /// A start pass: one invocation per index of the current chunk.
    Start,
    /// A stream's queue: one invocation per queued item, dispatched indirectly.
    Queue(StreamId),
    /// The chain's state buffer: one invocation per slot, items stored by an earlier kernel.
    State,
    /// A compaction boundary: one invocation per item queued there, dispatched indirectly.
    Boundary,
}

/// Which of a ping-pong boundary's two buffers a kernel uses in the current iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The items of this iteration.
    Current,
    /// The items of the next iteration.
    Next,
}

/// A kernel's end of a compaction boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Port {
    /// The boundary.
    pub boundary: BoundaryId,
    /// Which buffer of a ping-pong boundary.
    pub side: Side,
}

/// A compaction boundary: the queue of a chain's items in front of one of its loop kernels.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Boundary {
    /// The chain whose items it holds.
    pub chain: ChainId,
    /// Whether one kernel both reads and refills it, so it needs two buffers in turn.
    pub pingpong: bool,
}

/// One kernel of a layout.
#[derive(Debug, Clone)]
pub struct KernelPlan {
    /// Entry point name.
    pub name: String,
    /// The phase it belongs to.
    pub phase: PhaseId,
    /// The chain whose segment the kernel runs.
    pub chain: ChainId,
    /// The segment: positions in the chain's pass list.
    pub segment: Range<usize>,
    /// What feeds it.
    pub root: Root,
    /// Stream-fed chains called directly from this kernel (fused consumers).
    pub fused_chains: Vec<ChainId>,
    /// Whether the segment's loop passes repeat inside the kernel.
    pub loop_in_kernel: bool,
    /// Whether this kernel ends one host-driven loop iteration (it counts surviving items).
    pub ends_iteration: bool,
    /// Whether it takes new item indices from the chain's counter (regeneration and
    /// compaction policies, persistent threads).
    pub regenerates: bool,
    /// The compaction boundary it reads.
    pub input: Option<Port>,
    /// The compaction boundary it appends surviving or new items to.
    pub output: Option<Port>,
}

indexes!(BoundaryId => Boundary);
indexes!(KernelId => KernelPlan);

/// A step of a phase's schedule.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Run a kernel over the chunk's items or slots.
    Run(KernelId),
    /// Run the consumer kernel of a queued stream over its queue, then empty the queue.
    Drain(StreamId),
    /// Repeat the body while items of the chain are alive.
    Loop {
        /// The chain whose items are counted.
        chain: ChainId,
        /// The body of one iteration.
        body: Vec<Step>,
    },
}

/// A graph resolved for one layout.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The graph.
    pub graph: Graph,
    /// The layout's name.
    pub layout_name: String,
    /// The layout.
    pub layout: LayoutDecl,
    /// Kernels in declaration order.
    pub kernels: Vec<KernelPlan>,
    /// Per phase, the steps to run for each chunk.
    pub schedule: Vec<Vec<Step>>,
    /// Chains whose items are stored in state buffers between kernels.
    pub stored_chains: BTreeSet<ChainId>,
    /// Streams carried by queues (their consumers run in kernels of their own).
    pub queued_streams: BTreeSet<StreamId>,
    /// Compaction boundaries.
    pub boundaries: Vec<Boundary>,
}

impl Plan {
    /// Resolves `layout` (a name from the graph, listed in the error when unknown).
    pub fn new(graph: &Graph, layout: &str) -> Result<Plan> {
        Self::with_decl(graph, layout, graph.layout(layout)?.clone())
    }

    /// Resolves an explicit layout declaration.
    pub fn with_decl(graph: &Graph, layout_name: &str, layout: LayoutDecl) -> Result<Plan> {
        if layout.workgroup_size == 0 || layout.workgroup_size > 1024 {
            return Err(graph.error_in_layout(
                layout_name,
                layout_name,
                format!(
                    "layout '{layout_name}': workgroup_size {} is not in 1..=1024",
                    layout.workgroup_size
                ),
            ));
        }
        if layout.policy != Policy::Naive && layout.threads == Some(0) {
            return Err(graph.error_in_layout(
                layout_name,
                layout_name,
                format!("layout '{layout_name}': a pool of 0 threads"),
            ));
        }
        if let Some(at) = layout.regenerate_at {
            let why = if !(at > 0.0 && at <= 1.0) {
                Some(format!("regenerate_at {at} is not in (0, 1]"))
            } else if layout.policy != Policy::Regeneration || layout.loops != LoopMode::Host {
                Some("regenerate_at needs policy: Regeneration with loops: Host".to_string())
            } else {
                None
            };
            if let Some(why) = why {
                return Err(graph.error_in_layout(layout_name, layout_name, format!("layout '{layout_name}': {why}")));
            }
        }
        let groups = resolve_groups(graph, layout_name, &layout)?;
        let mut kernels = Vec::new();
        for (k, group) in groups.iter().enumerate() {
            kernels.push(plan_kernel(graph, layout_name, &layout, k, group)?);
        }
        let boundaries = apply_policy(graph, layout_name, &layout, &mut kernels)?;
        // Queue-fed chains need a kernel of their own.
        let queued_streams: BTreeSet<StreamId> = kernels
            .iter()
            .filter_map(|k| if let Root::Queue(s) = k.root { Some(s) } else { None })
            .collect();
        // Chains kept in slots between dispatches: split under Naive or Regeneration, or one
        // regenerating kernel that runs one loop iteration per dispatch.
        let stored_chains: BTreeSet<ChainId> = kernels
            .iter()
            .filter(|k| {
                k.root == Root::State || (k.regenerates && !k.loop_in_kernel && k.input.is_none() && k.output.is_none())
            })
            .map(|k| k.chain)
            .collect();
        let mut plan = Plan {
            graph: graph.clone(),
            layout_name: layout_name.to_string(),
            layout,
            kernels,
            schedule: Vec::new(),
            stored_chains,
            queued_streams,
            boundaries,
        };
        plan.check_streams(layout_name)?;
        plan.schedule = (0..graph.phases.len())
            .map(|ph| plan.phase_schedule(PhaseId(ph)))
            .collect();
        Ok(plan)
    }

    /// The passes of kernel `k`, including fused consumer chains.
    pub fn kernel_passes(&self, k: KernelId) -> Vec<PassId> {
        let kp = &self.kernels[k];
        let chains = &self.graph.chains;
        let mut out: Vec<PassId> = chains[kp.chain].passes[kp.segment.clone()].to_vec();
        for &c in &kp.fused_chains {
            out.extend(chains[c].passes.iter().copied());
        }
        out
    }

    /// Streams emitted by the passes of kernel `k` that travel through queues.
    pub fn queued_emits(&self, k: KernelId) -> Vec<StreamId> {
        let mut out: Vec<StreamId> = Vec::new();
        for p in self.kernel_passes(k) {
            for s in &self.graph.passes[p].emits {
                if self.queued_streams.contains(s) && !out.contains(s) {
                    out.push(*s);
                }
            }
        }
        out
    }

    /// The kernel consuming the queue of `stream`.
    pub fn consumer_kernel(&self, stream: StreamId) -> KernelId {
        KernelId(
            self.kernels
                .iter()
                .position(|k| k.root == Root::Queue(stream))
                .expect("queued streams have a consumer kernel"),
        )
    }

    /// Ids of the kernels, in order.
    pub fn kernel_ids(&self) -> impl Iterator<Item = KernelId> + use<> {
        (0..self.kernels.len()).map(KernelId)
    }

    fn check_streams(&self, layout_name: &str) -> Result<()> {
        for (k, kp) in self.kernels.iter().enumerate() {
            let k = KernelId(k);
            if !kp.loop_in_kernel {
                continue;
            }
            let chain = &self.graph.chains[kp.chain];
            let Some(ls) = chain.loop_start else { continue };
            for &p in &chain.passes[ls.max(kp.segment.start)..kp.segment.end] {
                for s in &self.graph.passes[p].emits {
                    if self.queued_streams.contains(s) {
                        let pass = &self.graph.passes[p].decl.name;
                        let s = &self.graph.streams[*s];
                        return Err(self.graph.error_in_layout(
                            layout_name,
                            pass,
                            format!(
                                "layout '{layout_name}': loop pass '{pass}' emits '{s}' inside the loop of kernel {}, so the queue of '{s}' \
                                 would have no bound; fuse its consumer '{}' into that kernel or use loops: Host",
                                self.kernels[k].name, s.decl.to,
                                s = s.name
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    fn phase_schedule(&self, ph: PhaseId) -> Vec<Step> {
        let root_chain = self.graph.phases[ph].chains[0];
        let mut ks: Vec<KernelId> = self
            .kernel_ids()
            .filter(|&k| self.kernels[k].chain == root_chain && !matches!(self.kernels[k].root, Root::Queue(_)))
            .collect();
        ks.sort_by_key(|&k| self.kernels[k].segment.start);
        let mut steps = Vec::new();
        let mut body = Vec::new();
        for k in ks {
            let mut run = vec![Step::Run(k)];
            run.extend(self.drains_after(k));
            let kp = &self.kernels[k];
            let in_host_loop = self.layout.loops == LoopMode::Host
                && (kp.regenerates
                    || self.graph.chains[kp.chain]
                        .loop_start
                        .is_some_and(|ls| kp.segment.end > ls));
            if in_host_loop {
                body.extend(run);
            } else {
                steps.extend(run);
            }
        }
        if !body.is_empty() {
            steps.push(Step::Loop {
                chain: root_chain,
                body,
            });
        }
        steps
    }

    fn drains_after(&self, k: KernelId) -> Vec<Step> {
        let mut out = Vec::new();
        for s in self.queued_emits(k) {
            out.push(Step::Drain(s));
            out.extend(self.drains_after(self.consumer_kernel(s)));
        }
        out
    }
}

/// Whether the graph's default constants, with the layout's, disable pass `p` of the declared
/// graph (its `enabled` is 0 with them; a condition naming a constant they do not give is not).
fn disabled_by_default(graph: &Graph, layout: &LayoutDecl, p: usize) -> bool {
    let Some(condition) = &graph.declared.passes[p].decl.enabled else {
        return false;
    };
    let vars: BTreeMap<String, f64> = graph
        .declared
        .constants
        .iter()
        .chain(&layout.constants)
        .map(|(k, v)| (k.clone(), v.as_f64()))
        .collect();
    Expr::parse(condition).and_then(|e| e.eval(&vars)) == Ok(0.0)
}

/// The layout's kernels with the live passes it leaves out that the graph's default constants
/// disable (another structure's passes, chosen by a constant) placed: a pass inside a chain
/// right after the pass before it in its chain (as declared, culled or not) that a kernel
/// lists, a pass that begins its chain (or follows none listed) in a kernel of its own, before
/// the first kernel that lists a pass declared after it.
fn placed_kernels(graph: &Graph, layout: &LayoutDecl) -> Vec<Vec<String>> {
    let declared = &graph.declared.passes;
    let order = |name: &str| declared.iter().position(|p| p.decl.name == name).unwrap_or(usize::MAX);
    let consumers: BTreeSet<&str> = graph.streams.iter().map(|s| s.decl.to.as_str()).collect();
    let entry = |q: usize| {
        matches!(declared[q].decl.role, Role::Start { .. }) || consumers.contains(declared[q].decl.name.as_str())
    };
    let mut kernels = layout.kernels.clone();
    for (i, p) in declared.iter().enumerate() {
        let name = &p.decl.name;
        let listed = |kernels: &[Vec<String>], n: &str| kernels.iter().any(|k| k.iter().any(|x| x == n));
        if listed(&kernels, name) || graph.is_culled(name) || !disabled_by_default(graph, layout, i) {
            continue;
        }
        let mut anchor = None;
        if !entry(i) {
            for q in (0..i).rev().filter(|&q| declared[q].decl.item == p.decl.item) {
                if listed(&kernels, &declared[q].decl.name) {
                    anchor = Some(&declared[q].decl.name);
                    break;
                }
                if entry(q) {
                    break;
                }
            }
        }
        match anchor {
            Some(a) => {
                let k = kernels
                    .iter()
                    .position(|k| k.contains(a))
                    .expect("the anchor is listed");
                let at = kernels[k].iter().position(|x| x == a).expect("the anchor is listed") + 1;
                kernels[k].insert(at, name.clone());
            }
            None => {
                let at = kernels
                    .iter()
                    .position(|k| k.iter().any(|x| order(x) > i && order(x) != usize::MAX))
                    .unwrap_or(kernels.len());
                kernels.insert(at, vec![name.clone()]);
            }
        }
    }
    kernels
}

fn resolve_groups(graph: &Graph, layout_name: &str, layout: &LayoutDecl) -> Result<Vec<Vec<PassId>>> {
    let mut seen: BTreeSet<PassId> = BTreeSet::new();
    let mut groups = Vec::new();
    for names in &placed_kernels(graph, layout) {
        let mut group = Vec::new();
        for name in names {
            if graph.declared.ops.iter().any(|o| o.name == *name) {
                return Err(graph.error_in_layout(
                    layout_name,
                    name,
                    format!("layout '{layout_name}' names operator '{name}'; operators run on their own and are not listed in layouts"),
                ));
            }
            if graph.is_culled(name) {
                continue;
            }
            let p = graph.pass_index(name).ok_or_else(|| {
                let known: Vec<&str> = graph.passes.iter().map(|p| p.decl.name.as_str()).collect();
                graph.error_in_layout(
                    layout_name,
                    name,
                    format!(
                        "layout '{layout_name}' names unknown pass '{name}' (passes: {})",
                        known.join(", ")
                    ),
                )
            })?;
            if !seen.insert(p) {
                return Err(graph.error_in_layout(
                    layout_name,
                    name,
                    format!("layout '{layout_name}' puts pass '{name}' in two kernels"),
                ));
            }
            group.push(p);
        }
        if !group.is_empty() {
            groups.push(group);
        }
    }
    if let Some(missing) = (0..graph.passes.len()).map(PassId).find(|p| !seen.contains(p)) {
        let name = &graph.passes[missing].decl.name;
        return Err(graph.error_in_layout(
            layout_name,
            layout_name,
            format!(
                "layout '{layout_name}' puts pass '{name}' in no kernel; it is enabled, and a layout may leave out only the passes the constants disable (those the graph's default constants disable are placed by their chain)"
            ),
        ));
    }
    Ok(groups)
}

/// The plan of kernel `k` of layout `layout_name`, the passes `group`, after checking that they
/// may share a kernel.
fn plan_kernel(
    graph: &Graph,
    layout_name: &str,
    layout: &LayoutDecl,
    k: usize,
    group: &[PassId],
) -> Result<KernelPlan> {
    let names: Vec<&str> = group.iter().map(|&p| graph.passes[p].decl.name.as_str()).collect();
    let check = KernelCheck {
        graph,
        layout_name,
        describe: format!("layout '{layout_name}': kernel [{}]", names.join(", ")),
    };
    let phase = check.one_phase(group)?;
    let segments = check.chain_segments(group)?;
    let (fused, (chain_index, segment)) = check.fused_and_root(group, &segments)?;
    let chain = &graph.chains[chain_index];
    let root = check.root(chain_index, &segment)?;
    let has_loop = chain.loop_start.is_some_and(|ls| segment.end > ls);
    let loop_in_kernel = check.loop_in_kernel(layout, chain_index, &segment, &root)?;
    let ends_iteration = !loop_in_kernel && has_loop && segment.end == chain.passes.len();
    let short: Vec<&str> = names.iter().take(3).copied().collect();
    let is_start = root == Root::Start;
    Ok(KernelPlan {
        name: format!("k{k}_{}", short.join("_")),
        phase,
        chain: chain_index,
        segment,
        root,
        fused_chains: fused,
        loop_in_kernel,
        ends_iteration,
        regenerates: is_start && loop_in_kernel && has_loop && layout.policy == Policy::Regeneration,
        input: None,
        output: None,
    })
}

/// The passes of a chain (by position) that a kernel holds.
type Segment = (ChainId, Range<usize>);

/// The checks of one kernel of a layout: what its errors name (`describe`: the layout and the
/// kernel's passes).
struct KernelCheck<'a> {
    graph: &'a Graph,
    layout_name: &'a str,
    describe: String,
}

impl KernelCheck<'_> {
    /// The one phase of the kernel's passes; an error when they span a phase boundary.
    fn one_phase(&self, group: &[PassId]) -> Result<PhaseId> {
        let graph = self.graph;
        let phase_of = |p: PassId| graph.phase_of_chain(graph.chain_of(p).0);
        let first_phase = phase_of(group[0]);
        if let Some(&other) = group.iter().find(|&&p| phase_of(p) != first_phase) {
            let (a, b) = (&graph.passes[group[0]].decl.name, &graph.passes[other].decl.name);
            let (pa, pb) = (first_phase, phase_of(other));
            let reason = graph.barrier_reason(pa, pb);
            return Err(graph.error_in_layout(
                self.layout_name,
                b,
                format!(
                    "{} fuses '{a}' (phase {pa}) with '{b}' (phase {pb}) across a phase boundary: {reason}",
                    self.describe
                ),
            ));
        }
        Ok(first_phase)
    }

    /// The kernel's passes as one contiguous segment per chain; an error at a gap.
    fn chain_segments(&self, group: &[PassId]) -> Result<Vec<Segment>> {
        let graph = self.graph;
        let mut segments = Vec::new();
        let mut chains_in: Vec<ChainId> = group.iter().map(|&p| graph.chain_of(p).0).collect();
        chains_in.sort();
        chains_in.dedup();
        for &c in &chains_in {
            let mut pos: Vec<usize> = group
                .iter()
                .map(|&p| graph.chain_of(p))
                .filter(|(cc, _)| *cc == c)
                .map(|(_, i)| i)
                .collect();
            pos.sort();
            let range = pos[0]..pos[pos.len() - 1] + 1;
            if range.len() != pos.len() {
                let chain = &graph.chains[c];
                let gap = range.clone().find(|i| !pos.contains(i)).expect("a gap exists");
                let gap_name = &graph.passes[chain.passes[gap]].decl.name;
                return Err(graph.error_in_layout(
                    self.layout_name,
                    gap_name,
                    format!(
                        "{} takes passes of the chain of '{}' around '{gap_name}' but not '{gap_name}' itself",
                        self.describe, chain.item
                    ),
                ));
            }
            segments.push((c, range));
        }
        Ok(segments)
    }

    /// The stream-fed chains whose producer is in the kernel (fused: called directly), and the
    /// one segment the kernel runs as its entry point; errors for a stream produced both inside
    /// and outside, a fused chain not whole, and other than one entry point.
    fn fused_and_root(&self, group: &[PassId], segments: &[Segment]) -> Result<(Vec<ChainId>, Segment)> {
        let graph = self.graph;
        let describe = &self.describe;
        let in_group = |p: PassId| group.contains(&p);
        let mut fused = Vec::new();
        let mut roots = Vec::new();
        for (c, range) in segments {
            let chain = &graph.chains[*c];
            let fused_here = match &chain.entry {
                ChainEntry::Stream(s) => {
                    let producers: Vec<PassId> = (0..graph.passes.len())
                        .map(PassId)
                        .filter(|&p| graph.passes[p].emits.contains(s))
                        .collect();
                    let s = &graph.streams[*s].name;
                    let inside = producers.iter().filter(|&&p| in_group(p)).count();
                    if inside > 0 && inside < producers.len() {
                        return Err(graph.error_in_layout(self.layout_name, s, format!("{describe}: stream '{s}' has producers inside and outside this kernel; its consumer must run in a kernel of its own")));
                    }
                    if inside > 0 && range.len() != chain.passes.len() {
                        return Err(graph.error_in_layout(self.layout_name, s, format!("{describe}: the chain of '{}' fed by '{s}' is fused with its producer, so it must be fused whole", chain.item)));
                    }
                    inside > 0
                }
                ChainEntry::Start(_) => false,
            };
            if fused_here {
                fused.push(*c);
            } else {
                roots.push((*c, range.clone()));
            }
        }
        if roots.len() != 1 {
            let firsts: Vec<String> = roots
                .iter()
                .map(|(c, r)| format!("'{}'", graph.passes[graph.chains[*c].passes[r.start]].decl.name))
                .collect();
            return Err(graph.error_in_layout(
                self.layout_name,
                &graph.passes[group[0]].decl.name,
                format!(
                    "{describe} has {} entry points ({}); a kernel runs one chain segment plus the consumers it feeds",
                    roots.len(),
                    firsts.join(", ")
                ),
            ));
        }
        Ok((fused, roots.remove(0)))
    }

    /// Where the entry segment `segment` of chain `c` gets its items: a Start pass, the state of
    /// an earlier kernel, or the queue of its stream (then the chain must run whole).
    fn root(&self, c: ChainId, segment: &Range<usize>) -> Result<Root> {
        let chain = &self.graph.chains[c];
        let root = if segment.start > 0 {
            Root::State
        } else {
            match &chain.entry {
                ChainEntry::Start(_) => Root::Start,
                ChainEntry::Stream(s) => Root::Queue(*s),
            }
        };
        if let Root::Queue(s) = root
            && segment.len() != chain.passes.len()
        {
            let s = &self.graph.streams[s].name;
            return Err(self.graph.error_in_layout(
                self.layout_name,
                s,
                format!(
                    "{}: the chain fed by queue '{s}' must run whole in one kernel",
                    self.describe
                ),
            ));
        }
        Ok(root)
    }

    /// Whether the kernel runs its chain's loop itself, by the layout's loop mode and policy;
    /// errors for the combinations that cannot run.
    fn loop_in_kernel(&self, layout: &LayoutDecl, c: ChainId, segment: &Range<usize>, root: &Root) -> Result<bool> {
        let (graph, layout_name, describe) = (self.graph, self.layout_name, &self.describe);
        let chain = &graph.chains[c];
        let has_loop = chain.loop_start.is_some_and(|ls| segment.end > ls);
        let whole_loop = chain
            .loop_start
            .is_some_and(|ls| segment.start <= ls && segment.end == chain.passes.len());
        Ok(match (root, layout.loops) {
            (Root::Queue(_), _) => true,
            (_, LoopMode::InKernel) if has_loop && layout.policy == Policy::Compaction => {
                return Err(graph.error_in_layout(
                    layout_name,
                    layout_name,
                    format!("{describe}: policy Compaction moves items between kernels, so it needs loops: Host"),
                ));
            }
            (Root::State, LoopMode::InKernel) if has_loop && layout.policy == Policy::Regeneration => {
                return Err(graph.error_in_layout(layout_name, layout_name, format!("{describe}: with in-kernel loops, policy Regeneration means persistent threads, so the start pass and the loop must share a kernel")));
            }
            (_, LoopMode::InKernel) => {
                if has_loop && !whole_loop {
                    let ls = chain.loop_start.unwrap_or(0);
                    let first = &graph.passes[chain.passes[ls]].decl.name;
                    return Err(graph.error_in_layout(layout_name, first, format!("{describe} splits the loop group of the chain of '{}' (from '{first}'); with loops: InKernel the loop group must be in one kernel", chain.item)));
                }
                has_loop
            }
            (Root::Start, LoopMode::Host) => {
                if has_loop && layout.policy == Policy::Naive {
                    let first = &graph.passes[chain.passes[segment.start]].decl.name;
                    return Err(graph.error_in_layout(layout_name, first, format!("{describe} puts the start pass '{first}' and a host-driven loop in one kernel; split the start pass into its own kernel, or regenerate (policy Regeneration or Compaction)")));
                }
                false
            }
            (Root::Boundary, _) => unreachable!("boundaries are assigned after planning"),
            (Root::State, LoopMode::Host) => {
                if has_loop && chain.loop_start.is_some_and(|ls| segment.start < ls) {
                    let first = &graph.passes[chain.passes[segment.start]].decl.name;
                    return Err(graph.error_in_layout(layout_name, first, format!("{describe} mixes the step '{first}' with loop passes; with loops: Host a kernel holds steps or loop passes, not both")));
                }
                false
            }
        })
    }
}

/// Applies the layout's policy to the chains with host-driven loops: their start kernel
/// regenerates, and under Compaction the loop kernels are joined by boundaries (queues of
/// the chain's items). Returns the boundaries.
fn apply_policy(
    graph: &Graph,
    layout_name: &str,
    layout: &LayoutDecl,
    kernels: &mut [KernelPlan],
) -> Result<Vec<Boundary>> {
    let mut boundaries = Vec::new();
    if layout.policy == Policy::Naive || layout.loops != LoopMode::Host {
        return Ok(boundaries);
    }
    for phase in &graph.phases {
        let c = phase.chains[0];
        let chain = &graph.chains[c];
        let Some(ls) = chain.loop_start else { continue };
        let start = kernels
            .iter()
            .position(|k| k.chain == c && k.root == Root::Start)
            .expect("every start chain has a start kernel");
        if kernels[start].segment.end < ls {
            let step = &graph.passes[chain.passes[kernels[start].segment.end]].decl.name;
            return Err(graph.error_in_layout(layout_name,
                step,
                format!("layout '{layout_name}': with policy {:?} the start kernel regenerates items every iteration, so it must also hold the step '{step}' that comes before the loop", layout.policy),
            ));
        }
        kernels[start].regenerates = true;
        if layout.policy != Policy::Compaction {
            continue;
        }
        let mut loop_kernels: Vec<usize> = (0..kernels.len())
            .filter(|&k| kernels[k].chain == c && kernels[k].segment.end > ls)
            .collect();
        loop_kernels.sort_by_key(|&k| kernels[k].segment.start);
        let m = loop_kernels.len();
        let first = boundaries.len();
        for _ in 0..m {
            boundaries.push(Boundary {
                chain: c,
                pingpong: m == 1,
            });
        }
        for (j, &k) in loop_kernels.iter().enumerate() {
            kernels[k].input = Some(Port {
                boundary: BoundaryId(first + j),
                side: Side::Current,
            });
            kernels[k].output = Some(Port {
                boundary: BoundaryId(first + (j + 1) % m),
                side: if m == 1 { Side::Next } else { Side::Current },
            });
            if kernels[k].root == Root::State {
                kernels[k].root = Root::Boundary;
            }
        }
        if !loop_kernels.contains(&start) {
            kernels[start].output = Some(Port {
                boundary: BoundaryId(first),
                side: Side::Current,
            });
        }
    }
    Ok(boundaries)
}
