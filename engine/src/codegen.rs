//! WGSL generation of the pass kernels: the prelude every kernel shares (frame record with
//! the parameters, constants, counters, resource bindings) and each kernel's own part (emit
//! functions, item load/store, the wrapper that calls the pass functions, the entry point).

use crate::access::Access;
use crate::graph::Graph;
use crate::ids::{ChainId, KernelId};
use crate::ir::{ConstValue, Scope, StateStorage};
use crate::limits::FRAME_BINDING;
use crate::plan::{Plan, Root};
use crate::resolve::{BufferRef, Resolved};
use std::fmt::Write;

/// Everything code generation needs beyond the plan.
#[derive(Clone)]
pub struct CodegenContext<'a> {
    /// The planned layout.
    pub plan: &'a Plan,
    /// Its sizes, capacities, bindings and control words.
    pub resolved: &'a Resolved,
    /// Cap on iterations of an in-kernel loop.
    pub max_loop_iterations: u32,
    /// Whether appends to queues and compaction boundaries take one atomic per subgroup
    /// (the target has subgroup operations) instead of one per item.
    pub subgroup_appends: bool,
    /// Whether a persistent thread takes at most its share of the items, ceil(items /
    /// threads), instead of items until none is left (see [`crate::Target`]).
    pub fair_shares: bool,
}

/// The words of a stored item a kernel moves through its slot, by index in the item's
/// flattened words: loaded before its passes run, stored after. Words a pass may write are
/// loaded too, so that a word a pass writes only on some paths keeps its stored value.
#[derive(Debug, Clone, PartialEq)]
pub struct SlotTraffic {
    /// Words loaded: those the passes may read or write.
    pub load: Vec<usize>,
    /// Words stored: those the passes may write.
    pub store: Vec<usize>,
    /// Words of the item.
    pub words: usize,
}

/// What kernel `k` moves of an item that stays in its slot (state kernels, and the items a
/// regenerating kernel continues); `None` where it moves whole items or none.
pub fn slot_traffic(plan: &Plan, resolved: &Resolved, k: KernelId) -> Option<SlotTraffic> {
    let g = &plan.graph;
    let kp = &plan.kernels[k];
    let chain = &g.chains[kp.chain];
    if !plan.stored_chains.contains(&kp.chain) {
        return None;
    }
    let positions = match kp.root {
        Root::State => kp.segment.clone(),
        Root::Start if kp.regenerates && !kp.loop_in_kernel => {
            chain.loop_start.unwrap_or(chain.passes.len()).max(kp.segment.start)..kp.segment.end
        }
        _ => return None,
    };
    if positions.is_empty() {
        return None;
    }
    let mut access = Access::default();
    for pos in positions {
        access.union(&resolved.access[g.passes[chain.passes[pos]].function()]);
    }
    let load = access.read.union(&access.write).map(|&w| w as usize).collect();
    Some(SlotTraffic {
        load,
        store: access.write.iter().map(|&w| w as usize).collect(),
        words: resolved.words[&chain.item].len(),
    })
}

/// `lg_slot`, which passes may read: the slot the thread's item holds in its chain's state
/// buffer (below `ITEM_SLOTS`, which a resource's count may use) in kernels of a chain stored
/// between kernels; the thread's index in others.
pub const SLOT_DECLARATION: &str = "var<private> lg_slot: u32;\n";

/// The WGSL type a parameter's field of the frame record has (a `bool` is held as `u32`).
fn parameter_field_type(v: &ConstValue) -> &'static str {
    match v {
        ConstValue::Bool(_) => "u32",
        other => other.wgsl_type(),
    }
}

/// WGSL statements that set `lg_slot` to the slot an append of one item claims from the
/// atomic counter `counter`. Per item: one atomic each. Per subgroup: the invocations that
/// reach the append together (any subset of the subgroup, in any control flow) are ranked by
/// an exclusive sum over the active invocations; the first of them (rank 0, the lowest active
/// invocation) adds the subgroup's total in one atomic, and `subgroupBroadcastFirst` hands
/// its base to the others. The slots claimed are the same set either way, so the counter's
/// final value, and with it the count of items past a capacity, is exact.
fn claim_slot(counter: &str, subgroup: bool) -> String {
    if !subgroup {
        return format!("    let lg_slot = atomicAdd(&{counter}, 1u);\n");
    }
    format!(
        "    let lg_rank = subgroupExclusiveAdd(1u);\n    let lg_total = subgroupAdd(1u);\n    var lg_base = 0u;\n    if (lg_rank == 0u) {{ lg_base = atomicAdd(&{counter}, lg_total); }}\n    let lg_slot = subgroupBroadcastFirst(lg_base) + lg_rank;\n"
    )
}

impl CodegenContext<'_> {
    fn graph(&self) -> &Graph {
        &self.plan.graph
    }

    fn binding(&self, b: &BufferRef) -> u32 {
        self.resolved.bindings[b]
    }

    /// The frame record: index, seed, first item and item count of the chunk, then the
    /// parameters; each parameter is also a private variable, set by the entry point.
    fn frame_record(&self) -> String {
        let mut s = String::from("struct Frame {\n    index: u32,\n    seed: u32,\n    base: u32,\n    count: u32,\n");
        for (name, v) in &self.resolved.parameters {
            let _ = writeln!(s, "    lg_{name}: {},", parameter_field_type(v));
        }
        s.push_str("}\n");
        for (name, v) in &self.resolved.parameters {
            let _ = writeln!(s, "var<private> {name}: {};", v.wgsl_type());
        }
        s.push_str("fn lg_parameters() {\n");
        for (name, v) in &self.resolved.parameters {
            let read = match v {
                ConstValue::Bool(_) => format!("frame.lg_{name} != 0u"),
                _ => format!("frame.lg_{name}"),
            };
            let _ = writeln!(s, "    {name} = {read};");
        }
        s.push_str("}\n");
        s
    }

    /// Shared declarations: frame record, constants, counters, engine buffers, resources.
    pub fn prelude(&self) -> String {
        let g = self.graph();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "// Generated by lightgraph-engine: graph '{}', layout '{}'.",
            g.name, self.plan.layout_name
        );
        s.push_str(&self.frame_record());
        s.push_str(FRAME_BINDING);
        s.push_str(SLOT_DECLARATION);
        let _ = writeln!(
            s,
            "@group(0) @binding({}) var<storage, read_write> lg_counters: array<atomic<u32>>;",
            self.binding(&BufferRef::Counters)
        );
        let _ = writeln!(
            s,
            "@group(0) @binding({}) var<storage, read_write> lg_control: array<atomic<u32>>;",
            self.binding(&BufferRef::Control)
        );
        for (name, v) in &self.resolved.constants {
            let _ = writeln!(s, "const {name}: {} = {};", v.wgsl_type(), v.wgsl_literal());
        }
        // Counts add up in workgroup memory (no register per counter held through the kernel:
        // VCMsk 7-9% faster on Sponza on an H100, docs/performance.md); `lg_flush` adds them up.
        for (i, c) in g.counters.iter().enumerate() {
            let _ = writeln!(s, "const COUNTER_{}: u32 = {i}u;", c.to_uppercase());
        }
        let _ = writeln!(
            s,
            "var<workgroup> lg_wg_counts: array<atomic<u32>, {}>;",
            g.counters.len().max(1)
        );
        s.push_str("fn count(counter: u32, n: u32) {\n    atomicAdd(&lg_wg_counts[counter], n);\n}\n");
        // Writable: a pass or operator writes it, it holds atomics, or it is transient (its
        // memory is shared, so every binding of it is read-write).
        let written = g.written_resources();
        for (name, r) in &g.resources {
            let writable = r.scope == Scope::Transient || r.ty.contains("atomic") || written.contains(name);
            let access = if writable { "read_write" } else { "read" };
            let ty = if r.count.is_some() {
                format!("array<{}>", r.ty)
            } else {
                r.ty.clone()
            };
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, {access}> {name}: {ty};",
                self.binding(&BufferRef::Resource(name.clone()))
            );
        }
        s
    }

    /// Emit functions that do nothing: enough to type-check the passes.
    pub fn stub_emits(&self) -> String {
        let mut s = String::new();
        for (name, st) in &self.graph().streams {
            let _ = writeln!(s, "fn emit_{name}(item: {}) {{}}", st.item);
        }
        s
    }

    fn index_expr(&self, storage: StateStorage, word: usize, words: usize, slot: &str, cap: &str) -> String {
        match storage {
            StateStorage::SoA => format!("{word}u * {cap} + {slot}"),
            StateStorage::AoS => format!("{slot} * {words}u + {word}u"),
        }
    }

    /// `lg_load_<suffix>` and `lg_store_<suffix>`, moving every word of an item.
    fn load_store(&self, suffix: &str, buffer: &str, item: &str, cap: &str) -> String {
        let all: Vec<usize> = (0..self.resolved.words[item].len()).collect();
        self.load_store_words(suffix, buffer, item, cap, [&all, &all])
    }

    /// `lg_load_<suffix>` moving the words `moved[0]` (the others stay zero) and
    /// `lg_store_<suffix>` moving the words `moved[1]`.
    fn load_store_words(&self, suffix: &str, buffer: &str, item: &str, cap: &str, moved: [&[usize]; 2]) -> String {
        let words = &self.resolved.words[item];
        let storage = self.plan.layout.state;
        let mut s = String::new();
        let _ = writeln!(s, "fn lg_load_{suffix}(slot: u32) -> {item} {{\n    var v: {item};");
        for &w in moved[0] {
            let idx = self.index_expr(storage, w, words.len(), "slot", cap);
            let word = &words[w];
            let _ = writeln!(s, "    v{} = bitcast<{}>({buffer}[{idx}]);", word.path, word.scalar);
        }
        s.push_str("    return v;\n}\n");
        let _ = writeln!(s, "fn lg_store_{suffix}(slot: u32, v: {item}) {{");
        for &w in moved[1] {
            let idx = self.index_expr(storage, w, words.len(), "slot", cap);
            let word = &words[w];
            let _ = writeln!(s, "    {buffer}[{idx}] = bitcast<u32>(v{});", word.path);
        }
        s.push_str("}\n");
        s
    }

    /// WGSL statements that run passes `passes` of a chain on `it` (a function variable):
    /// steps return from the enclosing function on `false`, loop passes repeat (capped).
    fn run_passes(
        &self,
        chain: ChainId,
        range: std::ops::Range<usize>,
        in_kernel_loop: bool,
        on_finish: &str,
    ) -> String {
        let g = self.graph();
        let c = &g.chains[chain];
        let mut s = String::new();
        let loop_start = c.loop_start.unwrap_or(usize::MAX);
        let steps_end = range.end.min(loop_start.max(range.start));
        for pos in range.start..steps_end {
            let f = g.passes[c.passes[pos]].function();
            let _ = writeln!(s, "    if (!{f}(&it)) {{ {on_finish}return; }}");
        }
        if range.end > loop_start {
            let body: Vec<&str> = (loop_start.max(range.start)..range.end)
                .map(|pos| g.passes[c.passes[pos]].function())
                .collect();
            if in_kernel_loop {
                let _ = writeln!(s, "    var lg_iterations = 0u;\n    loop {{");
                let _ = writeln!(
                    s,
                    "        if (lg_iterations >= {}u) {{ atomicAdd(&lg_control[{}], 1u); break; }}\n        lg_iterations += 1u;",
                    self.max_loop_iterations, self.resolved.control.loop_capped
                );
                for f in body {
                    let _ = writeln!(s, "        if (!{f}(&it)) {{ break; }}");
                }
                let _ = writeln!(s, "    }}\n    {on_finish}");
            } else {
                for f in body {
                    let _ = writeln!(s, "    if (!{f}(&it)) {{ {on_finish}return; }}");
                }
            }
        }
        s
    }

    /// `if (!f(&it)) { <fail> }` for the passes at `positions` of chain `c`.
    fn guarded_calls(&self, c: ChainId, positions: std::ops::Range<usize>, fail: &str) -> String {
        let g = self.graph();
        let mut s = String::new();
        for pos in positions {
            let f = g.passes[g.chains[c].passes[pos]].function();
            let _ = writeln!(s, "    if (!{f}(&it)) {{ {fail} }}");
        }
        s
    }

    /// The kernel-specific part of kernel `k`'s module.
    pub fn kernel(&self, k: KernelId) -> String {
        let g = self.graph();
        let kp = &self.plan.kernels[k];
        let names: Vec<&String> = self
            .plan
            .kernel_passes(k)
            .iter()
            .map(|&p| &g.passes[p].decl.name)
            .collect();
        let mut s = format!(
            "// Kernel {}: chain of '{}', passes {names:?}.\n",
            kp.name, g.chains[kp.chain].item
        );
        let queues = self.kernel_queues(k);
        s.push_str(&self.queue_storage(&queues));
        s.push_str(&self.emit_functions(k, &queues));
        s.push_str(&self.item_storage(k));
        s.push_str(&self.run_wrapper(k));
        s.push_str(&self.counter_flush());
        s.push_str(&self.entry_point(k));
        s
    }

    /// Queues kernel `k` touches: emitted into, or consumed.
    fn kernel_queues(&self, k: KernelId) -> Vec<String> {
        let mut queues: Vec<String> = self.plan.queued_emits(k);
        if let Root::Queue(q) = &self.plan.kernels[k].root {
            queues.push(q.clone());
        }
        queues
    }

    /// Capacity, binding and item load/store of each queue in `queues`.
    fn queue_storage(&self, queues: &[String]) -> String {
        let mut s = String::new();
        for q in queues {
            let item = &self.graph().streams[q].item;
            let cap = format!("LG_CAP_{}", q.to_uppercase());
            let _ = writeln!(s, "const {cap}: u32 = {}u;", self.resolved.queue_capacity[q]);
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, read_write> lg_queue_{q}: array<u32>;",
                self.binding(&BufferRef::Queue(q.clone()))
            );
            s.push_str(&self.load_store(&format!("queue_{q}"), &format!("lg_queue_{q}"), item, &cap));
        }
        s
    }

    /// Emit functions: direct calls for fused consumers, appends for queues, no-ops otherwise.
    fn emit_functions(&self, k: KernelId, queues: &[String]) -> String {
        let g = self.graph();
        let kp = &self.plan.kernels[k];
        let mut s = String::new();
        for (name, st) in &g.streams {
            let fused = kp
                .fused_chains
                .iter()
                .find(|&&fc| g.chains[fc].entry == crate::graph::ChainEntry::Stream(name.clone()));
            if let Some(&fc) = fused {
                let _ = writeln!(s, "fn lg_chain_{fc}(item: {}) {{\n    var it = item;", st.item);
                s.push_str(&self.run_passes(fc, 0..g.chains[fc].passes.len(), true, ""));
                s.push_str("}\n");
                let _ = writeln!(s, "fn emit_{name}(item: {}) {{ lg_chain_{fc}(item); }}", st.item);
            } else if queues.contains(name) && !matches!(&kp.root, Root::Queue(q) if q == name) {
                let counter = format!("lg_control[{}]", self.resolved.control.queue_append[name]);
                let _ = writeln!(
                    s,
                    "fn emit_{name}(item: {}) {{\n{}    if (lg_slot < LG_CAP_{}) {{ lg_store_queue_{name}(lg_slot, item); }} else {{ atomicAdd(&lg_control[{}], 1u); }}\n}}",
                    st.item,
                    claim_slot(&counter, self.subgroup_appends),
                    name.to_uppercase(),
                    self.resolved.control.queue_overflow[name]
                );
            } else {
                let _ = writeln!(s, "fn emit_{name}(item: {}) {{}}", st.item);
            }
        }
        s
    }

    /// Item storage of kernel `k`'s chain: slots of a stored chain, a regeneration pool,
    /// compaction boundaries.
    fn item_storage(&self, k: KernelId) -> String {
        let kp = &self.plan.kernels[k];
        let c = kp.chain;
        let item = &self.graph().chains[c].item;
        let mut s = String::new();
        if self.plan.stored_chains.contains(&c) {
            let cap = format!("LG_SLOTS_{c}");
            let _ = writeln!(s, "const {cap}: u32 = {}u;", self.resolved.state_capacity[&c]);
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, read_write> lg_state_{c}: array<u32>;",
                self.binding(&BufferRef::State(c))
            );
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, read_write> lg_alive_{c}: array<u32>;",
                self.binding(&BufferRef::Alive(c))
            );
            s.push_str(&self.load_store(&format!("state_{c}"), &format!("lg_state_{c}"), item, &cap));
            if let Some(t) = slot_traffic(self.plan, self.resolved, k) {
                let (suffix, buffer) = (format!("state_{c}_part"), format!("lg_state_{c}"));
                s.push_str(&self.load_store_words(&suffix, &buffer, item, &cap, [&t.load, &t.store]));
            }
        }
        if let Some(pool) = self.resolved.pools.get(&c) {
            let _ = writeln!(s, "const LG_POOL: u32 = {pool}u;");
        }
        if kp.input.is_some() || kp.output.is_some() {
            s.push_str(&self.boundary_storage(k));
        }
        s
    }

    /// The compaction boundaries kernel `k` reads and appends to.
    fn boundary_storage(&self, k: KernelId) -> String {
        let kp = &self.plan.kernels[k];
        let item = &self.graph().chains[kp.chain].item;
        let mut s = String::from(
            "struct LgBoundary {\n    count: atomic<u32>,\n    append: atomic<u32>,\n    pad0: u32,\n    pad1: u32,\n    words: array<u32>,\n}\n",
        );
        if kp.input.is_some() {
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, read_write> lg_in: LgBoundary;",
                self.binding(&BufferRef::BoundaryIn)
            );
            s.push_str(&self.load_store("in", "lg_in.words", item, "LG_POOL"));
        }
        if kp.output.is_some() {
            let _ = writeln!(
                s,
                "@group(0) @binding({}) var<storage, read_write> lg_out: LgBoundary;",
                self.binding(&BufferRef::BoundaryOut)
            );
            s.push_str(&self.load_store("out", "lg_out.words", item, "LG_POOL"));
            // A pure regeneration kernel appends behind the survivors its boundary's count
            // holds; every other kernel appends to a boundary whose count was consumed.
            let behind = if kp.input.is_none() {
                "atomicLoad(&lg_out.count) + "
            } else {
                ""
            };
            let _ = writeln!(
                s,
                "fn lg_append(v: {}) {{\n{}    lg_store_out({behind}lg_slot, v);\n}}",
                item,
                claim_slot("lg_out.append", self.subgroup_appends)
            );
        }
        s
    }

    /// The per-invocation wrapper `lg_run`: where the item comes from, the passes, where it
    /// goes.
    fn run_wrapper(&self, k: KernelId) -> String {
        let w = Wrapper::new(self, k);
        let (kp, chain, c) = (w.kp, w.chain, w.kp.chain);
        let mut s = String::from("fn lg_run(lg_i: u32) {\n    lg_slot = lg_i;\n");
        match &kp.root {
            Root::Queue(q) => {
                let _ = writeln!(s, "    var it = lg_load_queue_{q}(lg_i);");
                s.push_str(&self.run_passes(c, kp.segment.clone(), true, ""));
            }
            Root::Boundary => {
                s.push_str("    var it = lg_load_in(lg_i);\n");
                s.push_str(&self.guarded_calls(c, kp.segment.clone(), "return;"));
                s.push_str("    lg_append(it);\n");
            }
            Root::State => {
                let _ = writeln!(
                    s,
                    "    if (lg_alive_{c}[lg_i] == 0u) {{ return; }}\n    var it = lg_load_state_{c}_part(lg_i);"
                );
                s.push_str(&self.run_passes(c, kp.segment.clone(), kp.loop_in_kernel, &w.kill));
                if !w.ends_chain || !kp.loop_in_kernel && chain.loop_start.is_some() {
                    let _ = writeln!(s, "    lg_store_state_{c}_part(lg_i, it);");
                    s.push_str(&w.count_alive);
                }
            }
            Root::Start if !kp.regenerates => {
                let _ = writeln!(
                    s,
                    "    var it: {};\n    if (!{}(&it, frame.base + lg_i)) {{ {}return; }}",
                    chain.item, w.start, w.kill
                );
                s.push_str(&self.run_passes(c, 1..kp.segment.end, kp.loop_in_kernel, &w.kill));
                if w.stored && (!w.ends_chain || !kp.loop_in_kernel && chain.loop_start.is_some()) {
                    let _ = writeln!(s, "    lg_store_state_{c}(lg_i, it);\n    lg_alive_{c}[lg_i] = 1u;");
                }
            }
            Root::Start if kp.loop_in_kernel => s.push_str(&self.persistent_threads(&w)),
            Root::Start => s.push_str(&self.regeneration(&w)),
        }
        s.push_str("}\n");
        s
    }

    /// Persistent threads: take the next item whenever the current one is done. Each thread
    /// is counted when it starts and, after its loop, whether the loop ended as it should (no
    /// item left, or its share taken), so that a thread the driver stopped early is seen.
    fn persistent_threads(&self, w: &Wrapper) -> String {
        let g = self.graph();
        let (chain, c) = (w.chain, w.kp.chain);
        let body: Vec<String> = w
            .loop_range
            .clone()
            .map(|pos| format!("{}(&it)", g.passes[chain.passes[pos]].function()))
            .collect();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "    var it: {};\n    var alive = false;\n    var lg_iterations = 0u;\n    var lg_ended = 0u;",
            chain.item
        );
        let (started, finished) = self.resolved.control.persistent[&c];
        s.push_str(&self.count_threads(started, "1u"));
        let ended = "lg_ended = 1u; break;";
        let take = if self.fair_shares {
            let _ = writeln!(
                s,
                "    let lg_items = {};\n    let lg_share = lg_items / LG_POOL + select(0u, 1u, lg_items % LG_POOL != 0u);\n    var lg_taken = 0u;",
                w.items
            );
            format!("            if (lg_taken >= lg_share) {{ {ended} }}\n            lg_taken += 1u;\n")
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "    loop {{\n        if (!alive) {{\n{take}            let index = atomicAdd(&lg_control[{}], 1u);\n            if (index >= {}) {{ {ended} }}",
            self.resolved.control.next[&c], w.items
        );
        let _ = writeln!(s, "            alive = {}(&it, frame.base + index);", w.start);
        for pos in 1..w.steps_end {
            let _ = writeln!(
                s,
                "            alive = alive && {}(&it);",
                g.passes[chain.passes[pos]].function()
            );
        }
        let _ = writeln!(
            s,
            "            lg_iterations = 0u;\n            continue;\n        }}\n        if (lg_iterations >= {}u) {{ atomicAdd(&lg_control[{}], 1u); alive = false; continue; }}\n        lg_iterations += 1u;\n        alive = {};\n    }}",
            self.max_loop_iterations,
            self.resolved.control.loop_capped,
            body.join(" && ")
        );
        // After the loop every thread of a subgroup is there again (one atomic a subgroup).
        s.push_str(&self.count_threads(finished, "lg_ended"));
        s
    }

    /// WGSL statements that add `value` (a u32 expression) over the threads to control word
    /// `word`: summed over the subgroup and added by its first thread where the target has
    /// subgroup operations, one atomic a thread otherwise, and always on a driver that caps an
    /// invocation's loops (`fair_shares`): llvmpipe's subgroup sums are loops, which a thread
    /// past the cap runs once, so they would miscount exactly the threads to be found.
    fn count_threads(&self, word: u32, value: &str) -> String {
        if !self.subgroup_appends || self.fair_shares {
            return format!("    atomicAdd(&lg_control[{word}], {value});\n");
        }
        format!(
            "    {{\n        let lg_sum = subgroupAdd({value});\n        if (subgroupExclusiveAdd(1u) == 0u) {{ atomicAdd(&lg_control[{word}], lg_sum); }}\n    }}\n"
        )
    }

    /// Regenerate into an idle slot or a compaction boundary, then run one iteration of the
    /// loop passes the kernel holds.
    fn regeneration(&self, w: &Wrapper) -> String {
        let (kp, c) = (w.kp, w.kp.chain);
        let mut s = String::new();
        let _ = writeln!(s, "    var it: {};", w.chain.item);
        let has_loop = !w.loop_range.is_empty();
        // A continued item moves only what the loop passes touch; a fresh one is stored whole.
        let continued = w.stored && has_loop;
        if continued {
            s.push_str("    var lg_fresh = false;\n");
        }
        if w.stored {
            let _ = writeln!(s, "    if (lg_alive_{c}[lg_i] != 0u) {{");
            if has_loop {
                let _ = writeln!(s, "        it = lg_load_state_{c}_part(lg_i);");
            } else {
                s.push_str("        return;\n");
            }
            s.push_str("    } else {\n");
        } else if kp.input.is_some() {
            s.push_str("    if (lg_i < atomicLoad(&lg_in.count)) {\n        it = lg_load_in(lg_i);\n    } else {\n");
        } else {
            s.push_str("    let queued = atomicLoad(&lg_out.count);\n    if (lg_i >= LG_POOL - min(queued, LG_POOL)) { return; }\n    {\n");
        }
        if let (Some(&held), Some(at)) = (self.resolved.control.held.get(&c), self.plan.layout.regenerate_at) {
            // Refill only once enough of the pool is idle.
            let pool = self.resolved.pools[&c];
            let idle = ((at as f64 * pool as f64).ceil() as u64).clamp(1, pool);
            let _ = writeln!(
                s,
                "    if (LG_POOL - min(atomicLoad(&lg_control[{held}]), LG_POOL) < {idle}u) {{ return; }}"
            );
        }
        let _ = writeln!(
            s,
            "    let index = atomicAdd(&lg_control[{}], 1u);\n    if (index >= {}) {{ return; }}",
            self.resolved.control.next.get(&c).copied().unwrap_or(0),
            w.items
        );
        if continued {
            s.push_str("    lg_fresh = true;\n");
        }
        let _ = writeln!(s, "    if (!{}(&it, frame.base + index)) {{ return; }}", w.start);
        s.push_str(&self.guarded_calls(c, 1..w.steps_end, "return;"));
        s.push_str("    }\n");
        s.push_str(&self.guarded_calls(c, w.loop_range.clone(), &format!("{}return;", w.kill)));
        if continued {
            let _ = writeln!(
                s,
                "    if (lg_fresh) {{ lg_store_state_{c}(lg_i, it); }} else {{ lg_store_state_{c}_part(lg_i, it); }}\n    lg_alive_{c}[lg_i] = 1u;"
            );
            s.push_str(&w.count_alive);
        } else if w.stored {
            let _ = writeln!(s, "    lg_store_state_{c}(lg_i, it);\n    lg_alive_{c}[lg_i] = 1u;");
            s.push_str(&w.count_alive);
        } else {
            s.push_str("    lg_append(it);\n");
        }
        s
    }

    /// Counter flush: the workgroup's counts (`count` adds to them in workgroup memory), one
    /// global atomic per workgroup and counter.
    fn counter_flush(&self) -> String {
        let n = self.graph().counters.len();
        let wg = self.plan.layout.workgroup_size;
        let mut s = String::new();
        if n > 0 {
            s.push_str("fn lg_flush(lid: u32) {\n");
            let _ = writeln!(
                s,
                "    workgroupBarrier();\n    for (var c = lid; c < {n}u; c += {wg}u) {{\n        let v = atomicLoad(&lg_wg_counts[c]);\n        if (v != 0u) {{ atomicAdd(&lg_counters[c], v); }}\n    }}\n}}"
            );
        }
        s
    }

    /// The entry point: one invocation per item below the kernel's limit.
    fn entry_point(&self, k: KernelId) -> String {
        let kp = &self.plan.kernels[k];
        let wg = self.plan.layout.workgroup_size;
        let limit = match &kp.root {
            Root::Queue(q) => format!("atomicLoad(&lg_control[{}])", self.resolved.control.queue_count[q]),
            Root::Boundary => "atomicLoad(&lg_in.count)".to_string(),
            _ if self.resolved.pools.contains_key(&kp.chain) => "LG_POOL".to_string(),
            _ => self.resolved.domain_count_wgsl(kp.phase),
        };
        let parameters = if self.resolved.parameters.is_empty() {
            ""
        } else {
            "    lg_parameters();\n"
        };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "@compute @workgroup_size({wg})\nfn {}(@builtin(workgroup_id) lg_wid: vec3<u32>, @builtin(num_workgroups) lg_nwg: vec3<u32>, @builtin(local_invocation_index) lg_lid: u32) {{\n{parameters}    let lg_i = (lg_wid.y * lg_nwg.x + lg_wid.x) * {wg}u + lg_lid;\n    if (lg_i < {limit}) {{ lg_run(lg_i); }}",
            kp.name
        );
        if !self.graph().counters.is_empty() {
            s.push_str("    lg_flush(lg_lid);\n");
        }
        s.push_str("}\n");
        s
    }
}

/// What the wrapper of a kernel knows of its chain and segment.
struct Wrapper<'a> {
    kp: &'a crate::plan::KernelPlan,
    chain: &'a crate::graph::Chain,
    /// Whether the chain's items live in slots.
    stored: bool,
    /// What ends an item early: its alive flag cleared, for stored chains.
    kill: String,
    /// Items of the chunk: the record's count, or the GPU count of a counted phase.
    items: String,
    /// The alive count of an iteration-ending kernel of a stored chain.
    count_alive: String,
    /// The chain's start pass.
    start: &'a str,
    /// End of the kernel's step passes (before the loop).
    steps_end: usize,
    /// The kernel's loop passes.
    loop_range: std::ops::Range<usize>,
    /// Whether the kernel runs the chain's last pass.
    ends_chain: bool,
}

impl<'a> Wrapper<'a> {
    fn new(ctx: &'a CodegenContext, k: KernelId) -> Wrapper<'a> {
        let g = ctx.graph();
        let kp = &ctx.plan.kernels[k];
        let c = kp.chain;
        let chain = &g.chains[c];
        let stored = ctx.plan.stored_chains.contains(&c);
        let ls = chain.loop_start.unwrap_or(chain.passes.len());
        Wrapper {
            kp,
            chain,
            stored,
            kill: if stored {
                format!("lg_alive_{c}[lg_i] = 0u; ")
            } else {
                String::new()
            },
            items: ctx.resolved.domain_count_wgsl(kp.phase),
            count_alive: if kp.ends_iteration && stored {
                format!("    atomicAdd(&lg_control[{}], 1u);\n", ctx.resolved.control.alive[&c])
            } else {
                String::new()
            },
            start: g.passes[chain.passes[0]].function(),
            steps_end: kp.segment.end.min(ls),
            loop_range: ls.max(kp.segment.start)..kp.segment.end,
            ends_chain: kp.segment.end == chain.passes.len(),
        }
    }
}
