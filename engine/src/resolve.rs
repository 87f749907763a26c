//! The resolve stage, between planning and code generation: binding numbers, control words,
//! resource sizes (from naga's layouter), each phase's domain and chunks, thread pools and
//! queue capacities, the lifetime of every buffer, and which transient buffers share memory.

use crate::access::Access;
use crate::error::Result;
use crate::expr::Expr;
use crate::graph::{ChainEntry, FrameStep};
use crate::ids::{BoundaryId, ChainId, KernelId, OpId, PhaseId, ResourceId, StreamId, indexes};
use crate::ir::{ConstValue, PerCall, Scope};
use crate::limits::{Target, WORKGROUP};
use crate::memory::{Lifetime, MemoryPlan, Request};
use crate::operator::OpKind;
use crate::plan::{Plan, Root};
use crate::reflect::{self, Word};
use crate::scratch::{SortShape, scratch_name, scratch_words};
use std::collections::{BTreeMap, BTreeSet};

/// Most items a split chain keeps in flight when its layout does not say.
const MAX_DEFAULT_IN_FLIGHT: u64 = 1 << 22;
/// Default thread pool of regeneration and compaction layouts: enough items per host
/// iteration (about 8 times the threads an H100 keeps resident) to amortise each iteration's
/// dispatches.
pub const DEFAULT_POOL: u64 = 1 << 20;
/// The name a resource's count uses for [`Resolved::item_slots`].
pub const ITEM_SLOTS: &str = "ITEM_SLOTS";

/// Bytes of a boundary buffer's header (count, append, two spare words).
pub const BOUNDARY_HEADER: u64 = 16;

/// The buffers a kernel can bind.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum BufferRef {
    /// The per-chunk frame record (uniform, group 1, dynamic offset).
    Frame,
    /// Per-chunk counter sums.
    Counters,
    /// Control words: queue counts and overflows, alive counts, loop caps.
    Control,
    /// 64-bit counter totals (fold kernel only).
    Totals,
    /// Indirect dispatch arguments.
    Args,
    /// A graph resource.
    Resource(ResourceId),
    /// The state buffer of a stored chain.
    State(ChainId),
    /// The alive flags of a stored chain.
    Alive(ChainId),
    /// The queue of a stream.
    Queue(StreamId),
    /// The compaction boundary a kernel reads (bound to one of the physical buffers).
    BoundaryIn,
    /// The compaction boundary a kernel appends to.
    BoundaryOut,
    /// A physical boundary buffer: boundary and which of its two buffers.
    Boundary(BoundaryId, usize),
    /// Scratch buffer of an operator, numbered per operator: the partial sums of a scan's
    /// levels; a sort's other keys and values, digit histograms and their partial sums.
    Scratch(OpId, usize),
}

impl BufferRef {
    /// A name for reports.
    pub fn describe(&self, plan: &Plan) -> String {
        let g = &plan.graph;
        match self {
            BufferRef::Resource(r) => g.resources[*r].name.clone(),
            BufferRef::State(c) => format!("state of {} (chain {c})", g.chains[*c].item),
            BufferRef::Alive(c) => format!("alive flags of {} (chain {c})", g.chains[*c].item),
            BufferRef::Queue(q) => format!("queue '{}'", g.streams[*q].name),
            BufferRef::Boundary(b, side) => {
                format!("boundary {b}.{side} of {}", g.chains[plan.boundaries[*b].chain].item)
            }
            BufferRef::Scratch(o, i) => format!("{} of '{}'", scratch_name(&g.ops[*o].kind, *i), g.ops[*o].name),
            other => format!("{other:?}").to_lowercase(),
        }
    }
}

/// Where each control word lives in the control buffer.
#[derive(Debug, Clone, Default)]
pub struct ControlMap {
    /// Items in a stream's queue.
    pub queue_count: BTreeMap<StreamId, u32>,
    /// Items emitted into a stream's queue since its last commit.
    pub queue_append: BTreeMap<StreamId, u32>,
    /// Items a stream's queue had no room for.
    pub queue_overflow: BTreeMap<StreamId, u32>,
    /// Items of a stored chain alive after the last loop iteration.
    pub alive: BTreeMap<ChainId, u32>,
    /// The next item index of a regenerating chain.
    pub next: BTreeMap<ChainId, u32>,
    /// Items of a chain regenerating behind a `regenerate_at` gate alive after the iteration
    /// before: the alive count, moved here when an iteration begins.
    pub held: BTreeMap<ChainId, u32>,
    /// Items of the current chunk of a phase counted on the GPU.
    pub domain: BTreeMap<PhaseId, u32>,
    /// Elements an operator skipped for a key or place out of range.
    pub op_overflow: BTreeMap<OpId, u32>,
    /// In-kernel loops stopped by the iteration cap.
    pub loop_capped: u32,
    /// Per chain run by persistent threads: the threads that started and the threads that
    /// ended their loop as it ends (no item left, or their share taken). A thread the driver
    /// stopped early (an iteration cap, a watchdog) starts and never ends.
    pub persistent: BTreeMap<ChainId, (u32, u32)>,
    /// Number of words.
    pub len: u32,
}

/// A resource's size after specialisation.
#[derive(Debug, Clone)]
pub struct ResourceSize {
    /// Bytes per element, from naga's layouter.
    pub element_bytes: u32,
    /// Element count, or `None` for external resources (sized by their data).
    pub count: Option<u64>,
}

indexes!(ResourceId => ResourceSize);

/// The items a phase runs over.
#[derive(Debug, Clone)]
pub struct PhaseDomain {
    /// Count expression (per frame when it names parameters), or with `counted` the most.
    pub over: Expr,
    /// The resource counting the items on the GPU.
    pub counted: Option<ResourceId>,
    /// `over` with the default parameters (what buffers are sized for).
    pub default: u64,
    /// Most items per chunk.
    pub chunk: u64,
}

/// A planned graph resolved for a target: everything code generation and execution need
/// besides the kernels themselves.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Constants, the graph's and the host's.
    pub constants: BTreeMap<String, ConstValue>,
    /// Parameters with their defaults, in frame-record order.
    pub parameters: Vec<(String, ConstValue)>,
    /// Resource sizes, by id.
    pub sizes: Vec<ResourceSize>,
    /// Resources some live pass or operator touches, and the outputs: the ones allocated.
    pub used: BTreeSet<ResourceId>,
    /// Words per item of stored chains and queued streams, by item type.
    pub words: BTreeMap<String, Vec<Word>>,
    /// Words of its item each pass of a stored chain may read and write, by pass function.
    pub access: BTreeMap<String, Access>,
    /// Each phase's items.
    pub domains: Vec<PhaseDomain>,
    /// Thread pool of each regenerating chain (also the capacity of its boundaries).
    pub pools: BTreeMap<ChainId, u64>,
    /// Slots of stored chains.
    pub state_capacity: BTreeMap<ChainId, u64>,
    /// Capacity of queues.
    pub queue_capacity: BTreeMap<StreamId, u64>,
    /// Elements of each operator with the default parameters (the most a counted one runs).
    pub op_elements: BTreeMap<OpId, u64>,
    /// Words of each operator's scratch buffers, by index of [`BufferRef::Scratch`].
    pub op_scratch: BTreeMap<OpId, Vec<u64>>,
    /// How the target's radix sorts run (their scratch and their kernels follow it).
    pub sort_shape: SortShape,
    /// Control word layout.
    pub control: ControlMap,
    /// Binding numbers of kernels.
    pub bindings: BTreeMap<BufferRef, u32>,
    /// Memory of every engine-allocated buffer, and the lifetimes of the transient ones.
    pub memory: MemoryPlan<BufferRef>,
    /// Transient resources set to zero before each frame step, by step.
    pub clears: BTreeMap<usize, Vec<ResourceId>>,
    /// The most loop iterations an item of a chain runs, where the graph bounds them.
    pub loop_bounds: BTreeMap<ChainId, u32>,
}

/// Binding numbers: engine buffers, resources, stored chains, queues, boundaries.
fn bindings(plan: &Plan) -> BTreeMap<BufferRef, u32> {
    let g = &plan.graph;
    let mut refs = vec![
        BufferRef::Counters,
        BufferRef::Control,
        BufferRef::Totals,
        BufferRef::Args,
    ];
    refs.extend(g.resource_ids().map(BufferRef::Resource));
    for &c in &plan.stored_chains {
        refs.extend([BufferRef::State(c), BufferRef::Alive(c)]);
    }
    refs.extend(plan.queued_streams.iter().map(|&q| BufferRef::Queue(q)));
    if !plan.boundaries.is_empty() {
        refs.extend([BufferRef::BoundaryIn, BufferRef::BoundaryOut]);
    }
    refs.into_iter().enumerate().map(|(i, b)| (b, i as u32)).collect()
}

/// The control words of a plan.
fn control_map(plan: &Plan) -> ControlMap {
    let g = &plan.graph;
    let mut control = ControlMap::default();
    let mut next = 0u32;
    let mut word = || {
        next += 1;
        next - 1
    };
    for &q in &plan.queued_streams {
        control.queue_count.insert(q, word());
        control.queue_append.insert(q, word());
        control.queue_overflow.insert(q, word());
    }
    for &c in &plan.stored_chains {
        control.alive.insert(c, word());
    }
    for k in plan.kernels.iter().filter(|k| k.regenerates) {
        control.next.insert(k.chain, word());
    }
    for k in plan.kernels.iter().filter(|k| k.regenerates && k.loop_in_kernel) {
        let started = word();
        control.persistent.insert(k.chain, (started, word()));
    }
    if plan.layout.regenerate_at.is_some() {
        for k in plan
            .kernels
            .iter()
            .filter(|k| k.regenerates && plan.stored_chains.contains(&k.chain))
        {
            control.held.insert(k.chain, word());
        }
    }
    for ph in 0..g.phases.len() {
        if g.phase_domain(PhaseId(ph)).counted.is_some() {
            control.domain.insert(PhaseId(ph), word());
        }
    }
    for (o, op) in g.ops.iter().enumerate() {
        if matches!(
            op.kind,
            OpKind::Count { .. } | OpKind::Scatter { .. } | OpKind::Gather { .. } | OpKind::Sort { .. }
        ) {
            control.op_overflow.insert(OpId(o), word());
        }
    }
    control.loop_capped = word();
    control.len = next;
    control
}

impl Resolved {
    /// What code generation needs to compile every source together before sizes are known:
    /// constants, parameters, bindings and control words.
    pub fn for_reflection(plan: &Plan) -> Resolved {
        Resolved {
            constants: plan.graph.constants.clone(),
            parameters: plan.graph.parameters.iter().map(|(k, v)| (k.clone(), *v)).collect(),
            sizes: Vec::new(),
            used: BTreeSet::new(),
            words: BTreeMap::new(),
            access: BTreeMap::new(),
            domains: Vec::new(),
            pools: BTreeMap::new(),
            state_capacity: BTreeMap::new(),
            queue_capacity: BTreeMap::new(),
            op_elements: BTreeMap::new(),
            op_scratch: BTreeMap::new(),
            sort_shape: SortShape::PORTABLE,
            control: control_map(plan),
            bindings: bindings(plan),
            memory: MemoryPlan::default(),
            clears: BTreeMap::new(),
            loop_bounds: BTreeMap::new(),
        }
    }

    /// Completes the resolution of `plan` (whose graph holds the specialised constants),
    /// begun by [`Resolved::for_reflection`], with the types of `reflection` (every source
    /// compiled together) for `target`.
    pub fn complete(self, plan: &Plan, reflection: &naga::Module, target: &Target) -> Result<Resolved> {
        let mut resolved = self;
        let vars = resolved.variables();
        resolved.used = used_resources(plan);
        resolved.words = item_words(plan, reflection)?;
        resolved.access = pass_access(plan, reflection, &resolved.words);
        resolved.capacities(plan, target, &vars)?;
        let mut vars = vars;
        vars.insert(ITEM_SLOTS.to_string(), resolved.item_slots() as f64);
        resolved.sizes = resource_sizes(plan, reflection, &vars)?;
        resolved.operators(plan, &vars, target)?;
        resolved.memory = resolved.plan_memory(plan, target)?;
        resolved.clears = resolved.transient_clears(plan);
        resolved.loop_bounds = loop_bounds(plan, &vars)?;
        Ok(resolved)
    }

    /// The most slots of any stored chain (at least 1): what `lg_slot` stays below.
    pub fn item_slots(&self) -> u64 {
        self.state_capacity.values().copied().max().unwrap_or(1).max(1)
    }

    /// The constants and the parameters' defaults, as numbers for count expressions.
    pub fn variables(&self) -> BTreeMap<String, f64> {
        self.constants
            .iter()
            .chain(self.parameters.iter().map(|(k, v)| (k, v)))
            .map(|(k, v)| (k.clone(), v.as_f64()))
            .collect()
    }

    /// Domains, chunks, pools, state slots and queue capacities: the item state and queues
    /// of a chunk (or a pool) must each fit one binding.
    fn capacities(&mut self, plan: &Plan, target: &Target, vars: &BTreeMap<String, f64>) -> Result<()> {
        let g = &plan.graph;
        let per_call = stream_per_call(plan, vars)?;
        let fanout = queue_fanout(plan, &per_call);
        for ph in 0..g.phases.len() {
            let ph = PhaseId(ph);
            let root = g.phases[ph].chains[0];
            let domain = g.phase_domain(ph);
            let default = domain
                .over
                .count(vars)
                .map_err(|e| g.error_at(&g.passes[g.chains[root].passes[0]].decl.name, e))?;
            let mut per_item_bytes: u64 = 0;
            if let Some(w) = self
                .words
                .get(&g.chains[root].item)
                .filter(|_| plan.stored_chains.contains(&root) || plan.boundaries.iter().any(|b| b.chain == root))
            {
                per_item_bytes = 4 * w.len() as u64;
            }
            for (&q, f) in &fanout {
                if g.phase_of_chain(plan.kernels[plan.consumer_kernel(q)].chain) == ph {
                    per_item_bytes = per_item_bytes.max(4 * self.words[&g.streams[q].decl.item].len() as u64 * f);
                }
            }
            // A boundary buffer holds BOUNDARY_HEADER bytes before its items.
            let fit = target
                .max_binding_bytes
                .saturating_sub(BOUNDARY_HEADER)
                .checked_div(per_item_bytes)
                .map_or(u64::MAX, |f| f.max(1));
            let chunk = if plan.kernels.iter().any(|k| k.chain == root && k.regenerates) {
                let pool = plan.layout.threads.unwrap_or(DEFAULT_POOL).min(default.max(1)).min(fit);
                self.pools.insert(root, pool);
                default.max(1)
            } else if per_item_bytes > 0 {
                default
                    .max(1)
                    .min(plan.layout.max_items_in_flight.unwrap_or(MAX_DEFAULT_IN_FLIGHT))
                    .min(fit)
            } else {
                default.max(1)
            };
            self.domains.push(PhaseDomain {
                over: domain.over.clone(),
                counted: domain.counted,
                default,
                chunk,
            });
        }
        let slots = |c: ChainId, r: &Resolved| {
            r.pools
                .get(&c)
                .copied()
                .unwrap_or(r.domains[g.phase_of_chain(c).0].chunk)
        };
        self.state_capacity = plan.stored_chains.iter().map(|&c| (c, slots(c, self))).collect();
        self.queue_capacity = fanout
            .iter()
            .map(|(&q, f)| {
                let ph = g.phase_of_chain(plan.kernels[plan.consumer_kernel(q)].chain);
                (q, f * slots(g.phases[ph].chains[0], self))
            })
            .collect();
        Ok(())
    }

    /// Each operator's element count and scratch buffers.
    fn operators(&mut self, plan: &Plan, vars: &BTreeMap<String, f64>, target: &Target) -> Result<()> {
        let g = &plan.graph;
        self.sort_shape = SortShape::of(target);
        for (o, op) in g.ops.iter().enumerate() {
            let o = OpId(o);
            let n = match (&op.domain, &op.kind) {
                (Some(d), _) => d
                    .over
                    .count(vars)
                    .map_err(|e| g.error_at(&op.name, format!("operator '{}': {e}", op.name)))?,
                (None, OpKind::Clear { buffer, .. }) => self.elements(*buffer),
                (None, _) => unreachable!("only Clear may omit its domain"),
            };
            self.check_operator_fits(plan, o, n, vars)?;
            self.op_elements.insert(o, n);
            let tile = (WORKGROUP * target.scan_items) as u64;
            self.op_scratch
                .insert(o, scratch_words(&op.kind, n, tile, self.sort_shape));
        }
        Ok(())
    }

    /// Elements of a resource (external ones: unknown until the host supplies them, so 0).
    fn elements(&self, r: ResourceId) -> u64 {
        self.sizes[r].count.unwrap_or(0)
    }

    /// An operator's elements must fit the buffers it reads and writes per element.
    fn check_operator_fits(&self, plan: &Plan, o: OpId, n: u64, vars: &BTreeMap<String, f64>) -> Result<()> {
        let g = &plan.graph;
        let op = &g.ops[o];
        let per_element: Vec<&ResourceId> = match &op.kind {
            OpKind::Clear { buffer, first, value } => {
                let (buffer, name) = (*buffer, &g.resources[*buffer].name);
                let first = match first {
                    Some(e) => e
                        .count(vars)
                        .map_err(|e| g.error_at(&op.name, format!("operator '{}': first: {e}", op.name)))?,
                    None => 0,
                };
                if first + n > self.elements(buffer) && self.sizes[buffer].count.is_some() {
                    return Err(g.error_at(
                        &op.name,
                        format!(
                            "operator '{}' clears elements {first}..{} of '{name}', which has {}",
                            op.name,
                            first + n,
                            self.elements(buffer)
                        ),
                    ));
                }
                if value.bits() != 0 && self.sizes[buffer].element_bytes != 4 {
                    return Err(g.error_at(
                        &op.name,
                        format!(
                            "operator '{}' fills '{name}' with a non-zero word, but its elements are {} bytes; only 4-byte elements can be filled with a value",
                            op.name,
                            self.sizes[buffer].element_bytes
                        ),
                    ));
                }
                vec![]
            }
            OpKind::Scan { input, output } => vec![input, output],
            OpKind::Count { keys, slots, .. } => vec![keys, slots],
            OpKind::Scatter { keys, slots, input, .. } => [keys, slots].into_iter().chain(input).collect(),
            OpKind::Gather { indices, output, .. } => vec![indices, output],
            OpKind::Sort { keys, values, .. } => [keys].into_iter().chain(values).collect(),
        };
        for &b in per_element {
            let have = self.elements(b);
            if self.sizes[b].count.is_some() && have < n {
                let b = &g.resources[b].name;
                return Err(g.error_at(
                    &op.name,
                    format!("operator '{}' runs over {n} elements but '{b}' holds {have}", op.name),
                ));
            }
        }
        Ok(())
    }

    /// Bytes of every engine-allocated buffer, and the lifetimes of the transient ones.
    fn buffer_requests(&self, plan: &Plan) -> BTreeMap<BufferRef, Request> {
        let g = &plan.graph;
        let mut out = BTreeMap::new();
        let lifetime_of = |steps: &mut dyn Iterator<Item = usize>| -> Option<Lifetime> {
            let steps: Vec<usize> = steps.collect();
            Some(Lifetime {
                first: *steps.iter().min()?,
                last: *steps.iter().max()?,
            })
        };
        let phase_life = |ph: PhaseId| {
            let s = g.step_of_phase(ph);
            Some(Lifetime { first: s, last: s })
        };
        let step_resources: Vec<BTreeSet<ResourceId>> = (0..g.steps.len()).map(|s| g.step_resources(s)).collect();
        for r in g.resource_ids() {
            let scope = g.resources[r].decl.scope;
            if scope == Scope::External || !self.used.contains(&r) {
                continue;
            }
            let size = &self.sizes[r];
            let bytes = size.element_bytes as u64 * size.count.unwrap_or(1).max(1);
            let lifetime = match scope {
                Scope::Transient => lifetime_of(&mut (0..g.steps.len()).filter(|&s| step_resources[s].contains(&r))),
                _ => None,
            };
            out.insert(BufferRef::Resource(r), Request { bytes, lifetime });
        }
        for (&c, &cap) in &self.state_capacity {
            let life = phase_life(g.phase_of_chain(c));
            let words = self.words[&g.chains[c].item].len() as u64;
            out.insert(
                BufferRef::State(c),
                Request {
                    bytes: 4 * words * cap,
                    lifetime: life,
                },
            );
            out.insert(
                BufferRef::Alive(c),
                Request {
                    bytes: 4 * cap,
                    lifetime: life,
                },
            );
        }
        for (&q, &cap) in &self.queue_capacity {
            let c = plan.kernels[plan.consumer_kernel(q)].chain;
            out.insert(
                BufferRef::Queue(q),
                Request {
                    bytes: 4 * self.words[&g.streams[q].decl.item].len() as u64 * cap,
                    lifetime: phase_life(g.phase_of_chain(c)),
                },
            );
        }
        for (b, boundary) in plan.boundaries.iter().enumerate() {
            let words = self.words[&g.chains[boundary.chain].item].len() as u64;
            for side in 0..1 + boundary.pingpong as usize {
                out.insert(
                    BufferRef::Boundary(BoundaryId(b), side),
                    Request {
                        bytes: BOUNDARY_HEADER + 4 * words * self.pools[&boundary.chain],
                        lifetime: phase_life(g.phase_of_chain(boundary.chain)),
                    },
                );
            }
        }
        for (&o, scratch) in &self.op_scratch {
            let s = g
                .steps
                .iter()
                .position(|x| *x == FrameStep::Op(o))
                .expect("every operator is a step");
            for (i, &words) in scratch.iter().enumerate() {
                out.insert(
                    BufferRef::Scratch(o, i),
                    Request {
                        bytes: 4 * words.max(1),
                        lifetime: Some(Lifetime { first: s, last: s }),
                    },
                );
            }
        }
        out
    }

    /// Places every buffer; each must fit one binding.
    fn plan_memory(&self, plan: &Plan, target: &Target) -> Result<MemoryPlan<BufferRef>> {
        let requests = self.buffer_requests(plan);
        for (b, r) in &requests {
            if r.bytes > target.max_binding_bytes {
                let message = format!(
                    "{} needs {:.1} MiB but the adapter binds at most {:.1} MiB per storage buffer",
                    b.describe(plan),
                    r.bytes as f64 / 1048576.0,
                    target.max_binding_bytes as f64 / 1048576.0
                );
                let g = &plan.graph;
                return Err(match b {
                    BufferRef::Resource(r) => {
                        g.error_at_decl(&g.resources[*r].name, format!("{message}; make its count smaller"))
                    }
                    _ => g.error_in_layout(
                        &plan.layout_name,
                        &plan.layout_name,
                        format!(
                            "layout '{}': {message}; use fewer items per frame (or max_items_in_flight, threads)",
                            plan.layout_name
                        ),
                    ),
                });
            }
        }
        Ok(MemoryPlan::new(
            &requests,
            target.storage_offset_alignment.max(4),
            target.max_buffer_bytes,
            target.alias_transients,
        ))
    }

    /// Transient resources declared `clear: true`, by the step that first uses them.
    fn transient_clears(&self, plan: &Plan) -> BTreeMap<usize, Vec<ResourceId>> {
        let g = &plan.graph;
        let mut out: BTreeMap<usize, Vec<ResourceId>> = BTreeMap::new();
        for r in g.resource_ids().filter(|&r| g.resources[r].decl.clear) {
            if let Some(life) = self.memory.lifetimes.get(&BufferRef::Resource(r)) {
                out.entry(life.first).or_default().push(r);
            }
        }
        out
    }

    /// Items the current chunk of phase `ph` runs, as WGSL: the frame record's count, or
    /// the control word a GPU-counted phase's domain kernel wrote.
    pub fn domain_count_wgsl(&self, ph: PhaseId) -> String {
        match self.control.domain.get(&ph) {
            Some(w) => format!("atomicLoad(&lg_control[{w}])"),
            None => "frame.count".to_string(),
        }
    }
}

/// Resources the live passes and operators touch, and the outputs.
fn used_resources(plan: &Plan) -> BTreeSet<ResourceId> {
    let g = &plan.graph;
    let mut used: BTreeSet<ResourceId> = g.outputs.iter().filter_map(|o| g.resource_id(o)).collect();
    for s in 0..g.steps.len() {
        used.extend(g.step_resources(s));
    }
    used
}

/// Element size and count of every resource, by id.
fn resource_sizes(plan: &Plan, reflection: &naga::Module, vars: &BTreeMap<String, f64>) -> Result<Vec<ResourceSize>> {
    let g = &plan.graph;
    let mut sizes = Vec::new();
    for crate::graph::Resource { name, decl: r } in &g.resources {
        let element_bytes = reflect::element_size(reflection, name)
            .ok_or_else(|| g.error_at_decl(name, format!("resource '{name}': cannot lay out type '{}'", r.ty)))?;
        let count = match (&r.count, r.scope) {
            (_, Scope::External) => None,
            (Some(expr), _) => Some(
                Expr::parse(expr)
                    .and_then(|e| e.count(vars))
                    .map_err(|e| g.error_at_decl(name, format!("resource '{name}': {e}")))?,
            ),
            (None, _) => Some(1),
        };
        sizes.push(ResourceSize { element_bytes, count });
    }
    Ok(sizes)
}

/// The words of the items stored between kernels or carried by queues.
fn item_words(plan: &Plan, reflection: &naga::Module) -> Result<BTreeMap<String, Vec<Word>>> {
    let g = &plan.graph;
    let mut words = BTreeMap::new();
    let pooled_items = plan
        .stored_chains
        .iter()
        .chain(plan.boundaries.iter().map(|b| &b.chain))
        .map(|&c| &g.chains[c].item);
    for item in pooled_items.chain(plan.queued_streams.iter().map(|&q| &g.streams[q].decl.item)) {
        words.insert(
            item.clone(),
            reflect::flatten(reflection, item).map_err(|e| g.error_at(item, e))?,
        );
    }
    Ok(words)
}

/// The graph's loop bounds, evaluated with the constants, for its chains with a loop.
fn loop_bounds(plan: &Plan, vars: &BTreeMap<String, f64>) -> Result<BTreeMap<ChainId, u32>> {
    let g = &plan.graph;
    let mut bounds = BTreeMap::new();
    for (item, e) in &g.declared.file.loop_bounds {
        let n = Expr::parse(e)
            .and_then(|e| e.count(vars))
            .map_err(|why| g.error_at(item, format!("loop_bounds of '{item}': {why}")))?;
        let n = u32::try_from(n)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| g.error_at(item, format!("loop_bounds of '{item}': {n} is not 1 to 2^32 - 1")))?;
        for (c, chain) in g.chains.iter().enumerate() {
            if &chain.item == item && chain.loop_start.is_some() {
                bounds.insert(ChainId(c), n);
            }
        }
    }
    Ok(bounds)
}

/// What each pass of a stored chain may read and write of its item (every word where the
/// analysis finds no item pointer).
fn pass_access(
    plan: &Plan,
    reflection: &naga::Module,
    words: &BTreeMap<String, Vec<Word>>,
) -> BTreeMap<String, Access> {
    let g = &plan.graph;
    let mut analysis = crate::access::Analysis::new(reflection);
    let mut out = BTreeMap::new();
    for &c in &plan.stored_chains {
        let all: BTreeSet<u32> = (0..words[&g.chains[c].item].len() as u32).collect();
        for &p in &g.chains[c].passes {
            let f = g.passes[p].function();
            let access = analysis.pass(f).unwrap_or_else(|| Access {
                read: all.clone(),
                write: all.clone(),
            });
            out.insert(f.to_string(), access);
        }
    }
    out
}

/// Each stream's per_call, evaluated with the constants.
fn stream_per_call(plan: &Plan, vars: &BTreeMap<String, f64>) -> Result<BTreeMap<StreamId, u64>> {
    let g = &plan.graph;
    let mut per_call = BTreeMap::new();
    for id in g.stream_ids() {
        let (name, s) = (&g.streams[id].name, &g.streams[id].decl);
        let n = match &s.per_call {
            PerCall::Number(n) => *n as u64,
            PerCall::Expr(e) => Expr::parse(e)
                .and_then(|e| e.count(vars))
                .map_err(|why| g.error_at(e, format!("stream '{name}': per_call: {why}")))?,
        };
        if n == 0 {
            return Err(g.error_at(name, format!("stream '{name}': per_call {} is 0", s.per_call)));
        }
        per_call.insert(id, n);
    }
    Ok(per_call)
}

/// Queue items per invocation of a phase's root kernels (fan-out), producers first.
fn queue_fanout(plan: &Plan, per_call: &BTreeMap<StreamId, u64>) -> BTreeMap<StreamId, u64> {
    let mut fanout: BTreeMap<StreamId, u64> = BTreeMap::new();
    for _ in 0..=plan.kernels.len() {
        for k in plan.kernel_ids() {
            let per_invocation = match &plan.kernels[k].root {
                Root::Queue(q) => match fanout.get(q) {
                    Some(f) => *f,
                    None => continue,
                },
                _ => 1,
            };
            for (q, mult) in emits_per_invocation(plan, k, per_call) {
                let e = fanout.entry(q).or_insert(0);
                *e = (*e).max(per_invocation * mult);
            }
        }
    }
    fanout
}

/// For kernel `k`, the queued streams it emits into and how many items one invocation can
/// emit into each (per_call times the calls of producing passes per invocation).
fn emits_per_invocation(plan: &Plan, k: KernelId, per_call: &BTreeMap<StreamId, u64>) -> Vec<(StreamId, u64)> {
    let g = &plan.graph;
    let kp = &plan.kernels[k];
    // Calls of each chain per invocation: the root chain once; fused chains per emit.
    let mut calls: BTreeMap<ChainId, u64> = BTreeMap::new();
    calls.insert(kp.chain, 1);
    let mut out: BTreeMap<StreamId, u64> = BTreeMap::new();
    let mut pending = vec![kp.chain];
    while let Some(c) = pending.pop() {
        let n = calls[&c];
        let range = if c == kp.chain {
            kp.segment.clone()
        } else {
            0..g.chains[c].passes.len()
        };
        for &p in &g.chains[c].passes[range] {
            for &s in &g.passes[p].emits {
                let per = per_call[&s] * n;
                if plan.queued_streams.contains(&s) {
                    *out.entry(s).or_insert(0) += per;
                } else if let Some(&fc) = kp
                    .fused_chains
                    .iter()
                    .find(|&&fc| g.chains[fc].entry == ChainEntry::Stream(s))
                {
                    *calls.entry(fc).or_insert(0) += per;
                    pending.push(fc);
                }
            }
        }
    }
    out.into_iter().collect()
}
