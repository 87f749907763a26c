//! Compiling a planned graph into WGSL modules validated by naga: constants, pass checks
//! (signatures, declared versus actual resource use, declared emits), resource sizes from
//! naga's layouter, chunk and queue capacities, and one module per kernel.

use crate::codegen::{BufferRef, CodegenContext, ControlMap};
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::graph::ChainEntry;
use crate::ir::{ConstValue, PerCall, Role, Scope};
use crate::plan::{Plan, Root};
use crate::reflect::{self, Word};
use crate::wgsl::{ModuleSource, preprocess};
use std::collections::{BTreeMap, BTreeSet};

/// How a program is specialised: constant values and preprocessor flags.
#[derive(Debug, Clone, Default)]
pub struct Specialization {
    /// Constant values; they override the graph's defaults and add host constants.
    pub constants: BTreeMap<String, ConstValue>,
    /// Flags for `#if` in WGSL sources.
    pub flags: BTreeSet<String>,
}

/// Device properties that shape compilation.
#[derive(Debug, Clone)]
pub struct Target {
    /// naga capabilities of the device.
    pub capabilities: naga::valid::Capabilities,
    /// Largest storage buffer binding, in bytes.
    pub max_binding_bytes: u64,
    /// Largest number of workgroups per dispatch dimension.
    pub max_workgroups_per_dimension: u32,
    /// Cap on the iterations of in-kernel loops (a guard against hangs).
    pub max_loop_iterations: u32,
}

impl Default for Target {
    fn default() -> Self {
        Target {
            capabilities: naga::valid::Capabilities::all(),
            max_binding_bytes: 128 << 20,
            max_workgroups_per_dimension: 65535,
            max_loop_iterations: 1 << 16,
        }
    }
}

/// A resource's size after specialisation.
#[derive(Debug, Clone)]
pub struct ResourceSize {
    /// Bytes per element, from naga's layouter.
    pub element_bytes: u32,
    /// Element count, or `None` for external resources (sized by their data).
    pub count: Option<u64>,
}

/// One compiled kernel.
#[derive(Debug, Clone)]
pub struct KernelModule {
    /// Entry point name.
    pub name: String,
    /// The assembled WGSL with its source map.
    pub source: ModuleSource,
    /// The validated naga module.
    pub module: naga::Module,
    /// Buffers the entry point uses.
    pub uses: Vec<BindingUse>,
}

/// A buffer an entry point uses, as its WGSL declares it.
#[derive(Debug, Clone, PartialEq)]
pub struct BindingUse {
    /// Which buffer.
    pub buffer: BufferRef,
    /// Binding number in group 0.
    pub binding: u32,
    /// Declared `var<storage, read>`.
    pub read_only: bool,
    /// Declared `var<uniform>`.
    pub uniform: bool,
}

/// A planned graph compiled for a target and specialisation.
#[derive(Debug, Clone)]
pub struct Program {
    /// The plan.
    pub plan: Plan,
    /// All constants, defaults merged with the specialisation.
    pub constants: BTreeMap<String, ConstValue>,
    /// Resource sizes.
    pub sizes: BTreeMap<String, ResourceSize>,
    /// Binding numbers.
    pub bindings: BTreeMap<BufferRef, u32>,
    /// Items per phase (from the start pass's count expression).
    pub domains: Vec<u64>,
    /// Items per chunk for each phase.
    pub chunks: Vec<u64>,
    /// Words per item of stored chains and queued streams, by item type.
    pub words: BTreeMap<String, Vec<Word>>,
    /// Slots of stored chains.
    pub state_capacity: BTreeMap<usize, u64>,
    /// Capacity of queues.
    pub queue_capacity: BTreeMap<String, u64>,
    /// Thread pool of each regenerating chain (also the capacity of its boundaries).
    pub pools: BTreeMap<usize, u64>,
    /// Control word layout.
    pub control: ControlMap,
    /// Kernel modules, in plan order.
    pub kernels: Vec<KernelModule>,
    /// Argument kernels, one per queued stream: (stream, WGSL).
    pub args_kernels: Vec<(String, String)>,
    /// The counter fold kernel.
    pub fold_kernel: String,
    /// The target compiled for.
    pub target: Target,
}

/// Most items a split chain keeps in flight when its layout does not say.
const MAX_DEFAULT_IN_FLIGHT: u64 = 1 << 22;
/// Default thread pool of regeneration and compaction layouts: enough items per host
/// iteration (about 8 times the threads an H100 keeps resident) to amortise each iteration's
/// dispatches.
pub const DEFAULT_POOL: u64 = 1 << 20;

impl Program {
    /// Compiles `plan` for `target` with `spec`.
    pub fn compile(plan: &Plan, spec: &Specialization, target: &Target) -> Result<Program> {
        let g = &plan.graph;
        let mut constants = g.constants.clone();
        for (name, v) in &spec.constants {
            if let Some(default) = g.constants.get(name)
                && default.wgsl_type() != v.wgsl_type()
            {
                return Err(g.error_at(
                    name,
                    format!(
                        "constant '{name}' is {} in the graph but was given as {}",
                        default.wgsl_type(),
                        v.wgsl_type()
                    ),
                ));
            }
            constants.insert(name.clone(), *v);
        }
        let vars: BTreeMap<String, f64> = constants.iter().map(|(k, v)| (k.clone(), v.as_f64())).collect();

        // Sources shared by every kernel.
        let mut shared: Vec<(String, String)> = Vec::new();
        let mut files: Vec<String> = g.library.clone();
        for p in g.passes.iter().chain(&g.culled) {
            if !files.contains(&p.decl.source) {
                files.push(p.decl.source.clone());
            }
        }
        for f in &files {
            let text = g.vfs.read(f).map_err(|e| g.error_at(f, e.to_string()))?;
            shared.push((f.clone(), preprocess(f, &text, &spec.flags)?));
        }

        let mut bindings: BTreeMap<BufferRef, u32> = BTreeMap::new();
        for b in [
            BufferRef::Frame,
            BufferRef::Counters,
            BufferRef::Control,
            BufferRef::Totals,
            BufferRef::Args,
        ] {
            let n = bindings.len() as u32;
            bindings.insert(b, n);
        }
        for r in g.resources.keys() {
            let n = bindings.len() as u32;
            bindings.insert(BufferRef::Resource(r.clone()), n);
        }
        for &c in &plan.stored_chains {
            let n = bindings.len() as u32;
            bindings.insert(BufferRef::State(c), n);
            bindings.insert(BufferRef::Alive(c), n + 1);
        }
        for q in &plan.queued_streams {
            let n = bindings.len() as u32;
            bindings.insert(BufferRef::Queue(q.clone()), n);
        }
        if !plan.boundaries.is_empty() {
            for b in [BufferRef::BoundaryIn, BufferRef::BoundaryOut] {
                let n = bindings.len() as u32;
                bindings.insert(b, n);
            }
        }
        let written = g.written_resources();
        let writable =
            |name: &str| written.contains(name) || g.resources.get(name).is_some_and(|r| r.ty.contains("atomic"));

        // Control words.
        let mut control = ControlMap::default();
        let mut next = 0u32;
        for q in &plan.queued_streams {
            control.queue_count.insert(q.clone(), next);
            control.queue_append.insert(q.clone(), next + 1);
            control.queue_overflow.insert(q.clone(), next + 2);
            next += 3;
        }
        for &c in &plan.stored_chains {
            control.alive.insert(c, next);
            next += 1;
        }
        for k in plan.kernels.iter().filter(|k| k.regenerates) {
            control.next.insert(k.chain, next);
            next += 1;
        }
        if plan.layout.regenerate_at.is_some() {
            for k in plan
                .kernels
                .iter()
                .filter(|k| k.regenerates && plan.stored_chains.contains(&k.chain))
            {
                control.held.insert(k.chain, next);
                next += 1;
            }
        }
        control.loop_capped = next;
        control.len = next + 1;

        // Reflection module: the shared part with no-op emits.
        let empty = BTreeMap::new();
        let mut ctx = CodegenContext {
            plan,
            constants: &constants,
            bindings: &bindings,
            words: &BTreeMap::new(),
            state_capacity: &empty,
            pools: &BTreeMap::new(),
            queue_capacity: &BTreeMap::new(),
            control: &control,
            writable: &writable,
            max_loop_iterations: target.max_loop_iterations,
        };
        let mut reflection = ModuleSource::default();
        reflection.push("<generated prelude>", &ctx.prelude());
        for (f, text) in &shared {
            reflection.push(f, text);
        }
        reflection.push("<generated emits>", &ctx.stub_emits());
        let (rmod, rinfo) = reflection.compile(target.capabilities)?;
        check_passes(plan, &rmod, &rinfo)?;

        // Sizes.
        let mut sizes = BTreeMap::new();
        for (name, r) in &g.resources {
            let element_bytes = reflect::element_size(&rmod, name)
                .ok_or_else(|| g.error_at(name, format!("resource '{name}': cannot lay out type '{}'", r.ty)))?;
            let count = match (&r.count, r.scope) {
                (_, Scope::External) => None,
                (Some(expr), _) => Some(
                    Expr::parse(expr)
                        .and_then(|e| e.count(&vars))
                        .map_err(|e| g.error_at(expr, format!("resource '{name}': {e}")))?,
                ),
                (None, _) => Some(1),
            };
            sizes.insert(name.clone(), ResourceSize { element_bytes, count });
        }
        let mut words = BTreeMap::new();
        let pooled_items = plan
            .stored_chains
            .iter()
            .chain(plan.boundaries.iter().map(|b| &b.chain))
            .map(|&c| &g.chains[c].item);
        for item in pooled_items.chain(plan.queued_streams.iter().map(|q| &g.streams[q].item)) {
            words.insert(
                item.clone(),
                reflect::flatten(&rmod, item).map_err(|e| g.error_at(item, e))?,
            );
        }

        // Each stream's per_call, evaluated with the constants.
        let mut per_call = BTreeMap::new();
        for (name, s) in &g.streams {
            let n = match &s.per_call {
                PerCall::Number(n) => *n as u64,
                PerCall::Expr(e) => Expr::parse(e)
                    .and_then(|e| e.count(&vars))
                    .map_err(|why| g.error_at(e, format!("stream '{name}': per_call: {why}")))?,
            };
            if n == 0 {
                return Err(g.error_at(name, format!("stream '{name}': per_call {} is 0", s.per_call)));
            }
            per_call.insert(name.clone(), n);
        }
        // Queue items per invocation of a phase's root kernels (fan-out), producers first.
        let mut fanout: BTreeMap<String, u64> = BTreeMap::new();
        for _ in 0..=plan.kernels.len() {
            for (k, kp) in plan.kernels.iter().enumerate() {
                let per_invocation = match &kp.root {
                    Root::Queue(q) => match fanout.get(q) {
                        Some(f) => *f,
                        None => continue,
                    },
                    _ => 1,
                };
                for (q, mult) in emits_per_invocation(plan, k, &per_call) {
                    let e = fanout.entry(q).or_insert(0);
                    *e = (*e).max(per_invocation * mult);
                }
            }
        }
        // Domains, chunks and pools: the item state and queues of a chunk (or a pool) must each
        // fit one binding.
        let mut domains = Vec::new();
        let mut chunks = Vec::new();
        let mut pools = BTreeMap::new();
        for (ph, phase) in g.phases.iter().enumerate() {
            let root = phase.chains[0];
            let ChainEntry::Start(over) = &g.chains[root].entry else {
                unreachable!("phases begin with a start chain")
            };
            let domain = over
                .count(&vars)
                .map_err(|e| g.error_at(&g.passes[g.chains[root].passes[0]].decl.name, e))?;
            let mut per_item_bytes: u64 = 0;
            if let Some(w) = words
                .get(&g.chains[root].item)
                .filter(|_| plan.stored_chains.contains(&root) || plan.boundaries.iter().any(|b| b.chain == root))
            {
                per_item_bytes = 4 * w.len() as u64;
            }
            for (q, f) in &fanout {
                if g.phase_of_chain(plan.kernels[plan.consumer_kernel(q)].chain) == ph {
                    per_item_bytes = per_item_bytes.max(4 * words[&g.streams[q].item].len() as u64 * f);
                }
            }
            let fit = target
                .max_binding_bytes
                .checked_div(per_item_bytes)
                .map_or(u64::MAX, |f| f.max(1));
            if plan.kernels.iter().any(|k| k.chain == root && k.regenerates) {
                pools.insert(
                    root,
                    plan.layout.threads.unwrap_or(DEFAULT_POOL).min(domain.max(1)).min(fit),
                );
                chunks.push(domain.max(1));
            } else if per_item_bytes > 0 {
                chunks.push(
                    domain
                        .max(1)
                        .min(plan.layout.max_items_in_flight.unwrap_or(MAX_DEFAULT_IN_FLIGHT))
                        .min(fit),
                );
            } else {
                chunks.push(domain.max(1));
            }
            domains.push(domain);
        }
        let slots = |c: usize| pools.get(&c).copied().unwrap_or(chunks[g.phase_of_chain(c)]);
        let state_capacity: BTreeMap<usize, u64> = plan.stored_chains.iter().map(|&c| (c, slots(c))).collect();
        let queue_capacity: BTreeMap<String, u64> = fanout
            .iter()
            .map(|(q, f)| {
                (
                    q.clone(),
                    f * slots(g.phases[g.phase_of_chain(plan.kernels[plan.consumer_kernel(q)].chain)].chains[0]),
                )
            })
            .collect();

        // Kernel modules.
        ctx.words = &words;
        ctx.state_capacity = &state_capacity;
        ctx.queue_capacity = &queue_capacity;
        ctx.pools = &pools;
        let prelude = ctx.prelude();
        let mut kernels = Vec::new();
        for (k, kp) in plan.kernels.iter().enumerate() {
            let mut src = ModuleSource::default();
            src.push("<generated prelude>", &prelude);
            for (f, text) in &shared {
                src.push(f, text);
            }
            src.push(&format!("<generated kernel {}>", kp.name), &ctx.kernel(k));
            let (module, info) = src.compile(target.capabilities).map_err(|e| match e {
                Error::Shader(m) => Error::Shader(format!("kernel {} of layout '{}': {m}", kp.name, plan.layout_name)),
                other => other,
            })?;
            let uses = entry_uses(&module, &info, &bindings);
            kernels.push(KernelModule {
                name: kp.name.clone(),
                source: src,
                module,
                uses,
            });
        }
        let max_groups = target.max_workgroups_per_dimension;
        let args_kernels = plan
            .queued_streams
            .iter()
            .enumerate()
            .map(|(i, q)| {
                let name = format!("lg_args_{q}");
                let wgsl = crate::codegen::ArgsKernel {
                    name: &name,
                    control_binding: bindings[&BufferRef::Control],
                    args_binding: bindings[&BufferRef::Args],
                    count_word: control.queue_count[q],
                    append_word: control.queue_append[q],
                    capacity: queue_capacity[q],
                    args_offset: 3 * i as u32,
                    workgroup: plan.layout.workgroup_size,
                    max_groups,
                }
                .wgsl();
                (q.clone(), wgsl)
            })
            .collect();
        let fold_kernel = crate::codegen::fold_kernel(
            bindings[&BufferRef::Counters],
            bindings[&BufferRef::Totals],
            g.counters.len(),
        );
        Ok(Program {
            plan: plan.clone(),
            constants,
            sizes,
            bindings,
            domains,
            chunks,
            words,
            state_capacity,
            queue_capacity,
            pools,
            control,
            kernels,
            args_kernels,
            fold_kernel,
            target: target.clone(),
        })
    }

    /// Bytes of the engine-allocated buffers (resources with known counts, states, alive
    /// flags, queues): the layout's GPU memory besides external scene data.
    pub fn allocated_bytes(&self) -> BTreeMap<String, u64> {
        let mut out = BTreeMap::new();
        for (name, s) in &self.sizes {
            if let Some(count) = s.count {
                out.insert(name.clone(), s.element_bytes as u64 * count);
            }
        }
        let g = &self.plan.graph;
        for (&c, &cap) in &self.state_capacity {
            let item = &g.chains[c].item;
            out.insert(
                format!("state of {item} (chain {c})"),
                4 * self.words[item].len() as u64 * cap,
            );
            out.insert(format!("alive flags of {item} (chain {c})"), 4 * cap);
        }
        for (b, boundary) in self.plan.boundaries.iter().enumerate() {
            let item = &g.chains[boundary.chain].item;
            let one = 16 + 4 * self.words[item].len() as u64 * self.pools[&boundary.chain];
            out.insert(format!("boundary {b} of {item}"), one * (1 + boundary.pingpong as u64));
        }
        for (q, &cap) in &self.queue_capacity {
            out.insert(
                format!("queue '{q}'"),
                4 * self.words[&g.streams[q].item].len() as u64 * cap,
            );
        }
        out
    }
}

/// For kernel `k`, the queued streams it emits into and how many items one invocation can
/// emit into each (per_call times the calls of producing passes per invocation).
fn emits_per_invocation(plan: &Plan, k: usize, per_call: &BTreeMap<String, u64>) -> Vec<(String, u64)> {
    let g = &plan.graph;
    let kp = &plan.kernels[k];
    // Calls of each chain per invocation: the root chain once; fused chains per emit.
    let mut calls: BTreeMap<usize, u64> = BTreeMap::new();
    calls.insert(kp.chain, 1);
    let mut out: BTreeMap<String, u64> = BTreeMap::new();
    let mut pending = vec![kp.chain];
    while let Some(c) = pending.pop() {
        let n = calls[&c];
        let range = if c == kp.chain {
            kp.segment.clone()
        } else {
            0..g.chains[c].passes.len()
        };
        for &p in &g.chains[c].passes[range] {
            for s in &g.passes[p].decl.emits {
                let per = per_call[s] * n;
                if plan.queued_streams.contains(s) {
                    *out.entry(s.clone()).or_insert(0) += per;
                } else if let Some(&fc) = kp
                    .fused_chains
                    .iter()
                    .find(|&&fc| g.chains[fc].entry == ChainEntry::Stream(s.clone()))
                {
                    *calls.entry(fc).or_insert(0) += per;
                    pending.push(fc);
                }
            }
        }
    }
    out.into_iter().collect()
}

/// The buffers the module's (single) entry point uses, from naga's analysis.
pub fn entry_uses(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    bindings: &BTreeMap<BufferRef, u32>,
) -> Vec<BindingUse> {
    let ep = info.get_entry_point(0);
    let by_number: BTreeMap<u32, &BufferRef> = bindings.iter().map(|(b, n)| (*n, b)).collect();
    let mut out = Vec::new();
    for (h, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        if ep[h].is_empty() {
            continue;
        }
        let Some(buffer) = by_number.get(&rb.binding) else {
            continue;
        };
        let (read_only, uniform) = match var.space {
            naga::AddressSpace::Uniform => (true, true),
            naga::AddressSpace::Storage { access } => (!access.contains(naga::StorageAccess::STORE), false),
            _ => continue,
        };
        out.push(BindingUse {
            buffer: (*buffer).clone(),
            binding: rb.binding,
            read_only,
            uniform,
        });
    }
    out
}

/// Functions called (transitively) by `f`, including itself.
fn callees(module: &naga::Module, f: naga::Handle<naga::Function>) -> BTreeSet<naga::Handle<naga::Function>> {
    fn walk(block: &naga::Block, out: &mut Vec<naga::Handle<naga::Function>>) {
        for st in block.iter() {
            match st {
                naga::Statement::Call { function, .. } => out.push(*function),
                naga::Statement::Block(b) => walk(b, out),
                naga::Statement::If { accept, reject, .. } => {
                    walk(accept, out);
                    walk(reject, out);
                }
                naga::Statement::Switch { cases, .. } => cases.iter().for_each(|c| walk(&c.body, out)),
                naga::Statement::Loop { body, continuing, .. } => {
                    walk(body, out);
                    walk(continuing, out);
                }
                _ => {}
            }
        }
    }
    let mut seen = BTreeSet::new();
    let mut stack = vec![f];
    while let Some(h) = stack.pop() {
        if seen.insert(h) {
            let mut direct = Vec::new();
            walk(&module.functions[h].body, &mut direct);
            stack.extend(direct);
        }
    }
    seen
}

/// Checks every pass function against its declaration: signature, resource use, emits.
fn check_passes(plan: &Plan, module: &naga::Module, info: &naga::valid::ModuleInfo) -> Result<()> {
    let g = &plan.graph;
    let find_fn = |name: &str| {
        module
            .functions
            .iter()
            .find(|(_, f)| f.name.as_deref() == Some(name))
            .map(|(h, _)| h)
    };
    let type_name = |ty: naga::Handle<naga::Type>| {
        module.types[ty]
            .name
            .clone()
            .unwrap_or_else(|| format!("{:?}", module.types[ty].inner))
    };
    for p in &g.passes {
        let d = &p.decl;
        let fname = p.function();
        let expected = match d.role {
            Role::Start { .. } => format!("fn {fname}(item: ptr<function, {}>, index: u32) -> bool", d.item),
            _ => format!("fn {fname}(item: ptr<function, {}>) -> bool", d.item),
        };
        let bad = |why: String| Error::Shader(format!("{}: pass '{}': {why}; expected `{expected}`", d.source, d.name));
        let h = find_fn(fname).ok_or_else(|| bad(format!("no function '{fname}' in {}", d.source)))?;
        let f = &module.functions[h];
        let want_args = if matches!(d.role, Role::Start { .. }) { 2 } else { 1 };
        if f.arguments.len() != want_args {
            return Err(bad(format!("it takes {} arguments", f.arguments.len())));
        }
        match &module.types[f.arguments[0].ty].inner {
            naga::TypeInner::Pointer {
                base,
                space: naga::AddressSpace::Function,
            } if type_name(*base) == d.item => {}
            _ => {
                return Err(bad(format!("its first argument is {}", type_name(f.arguments[0].ty))));
            }
        }
        if want_args == 2
            && !matches!(
                module.types[f.arguments[1].ty].inner,
                naga::TypeInner::Scalar(naga::Scalar::U32)
            )
        {
            return Err(bad("its second argument is not u32".into()));
        }
        match &f.result {
            Some(r) if matches!(module.types[r.ty].inner, naga::TypeInner::Scalar(naga::Scalar::BOOL)) => {}
            _ => return Err(bad("it does not return bool".into())),
        }
        let fi = &info[h];
        for (gh, var) in module.global_variables.iter() {
            let Some(name) = var.name.as_deref() else {
                continue;
            };
            if !g.resources.contains_key(name) {
                continue;
            }
            let uses = fi[gh];
            if uses.contains(naga::valid::GlobalUse::WRITE) && !d.writes.iter().any(|w| w == name) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' writes resource '{name}' but does not declare it in `writes` ({})",
                    d.source, d.name, p.origin
                )));
            }
            if !uses.is_empty() && !d.reads.iter().chain(d.writes.iter()).any(|w| w == name) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' reads resource '{name}' but does not declare it in `reads` ({})",
                    d.source, d.name, p.origin
                )));
            }
        }
        let called: BTreeSet<String> = callees(module, h)
            .iter()
            .filter_map(|&c| module.functions[c].name.clone())
            .collect();
        for s in g.streams.keys() {
            if called.contains(&format!("emit_{s}")) && !d.emits.contains(s) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' calls emit_{s} but does not declare `emits: [\"{s}\"]` ({})",
                    d.source, d.name, p.origin
                )));
            }
        }
    }
    Ok(())
}
