//! Compiling a graph in a layout ([`compile`], the engine's one compile entry), in the
//! engine's stages: specialise to the constants (which culls), plan the layout on the live
//! graph, reflect over the WGSL with naga (pass checks, sizes, item words), resolve
//! (capacities, lifetimes, shared memory), then generate every kernel (pass kernels without
//! the functions they never call, the engine's own small kernels, the operators') and validate
//! each with naga.

use crate::codegen::CodegenContext;
use crate::collective::op_kernels;
use crate::derive;
use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::ids::{OpId, PhaseId, StreamId};
use crate::internal::{ArgsKernel, CommitKernel, DomainKernel, fold_kernel, roll_kernel, zero_kernel};
use crate::ir::{ConstValue, LayoutDecl};
use crate::limits::Target;
use crate::plan::Plan;
use crate::reflect;
use crate::resolve::{BufferRef, Resolved};
use crate::scan::Groups;
use crate::wgsl::ModuleSource;
use std::collections::{BTreeMap, BTreeSet};

/// How a program is specialised: constant values and preprocessor flags.
#[derive(Debug, Clone, Default)]
pub struct Specialization {
    /// Constant values; they override the graph's defaults and add host constants.
    pub constants: BTreeMap<String, ConstValue>,
    /// Flags for `#if` in WGSL sources.
    pub flags: BTreeSet<String>,
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
    /// The runtime checks wgpu compiles into it.
    pub checks: RuntimeChecks,
}

/// The runtime checks wgpu compiles into a kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RuntimeChecks {
    /// Bounds checks and a loop guard in every loop: a graph's pass kernels.
    All,
    /// Bounds checks only: pass kernels of a layout whose loops all end (`loop_guards: false`).
    NoLoopGuards,
    /// None: the engine wrote the kernel and guards every index and loop itself.
    None,
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

/// The kernels of an operator, each with its workgroups.
#[derive(Debug, Clone)]
pub struct OpModules {
    /// The kernels in the order they run.
    pub kernels: Vec<(KernelModule, Groups)>,
}

/// A planned graph compiled for a target and specialisation.
#[derive(Debug, Clone)]
pub struct Program {
    /// The plan of the live graph.
    pub plan: Plan,
    /// Sizes, capacities, control words, bindings and memory.
    pub resolved: Resolved,
    /// Pass kernels, in plan order.
    pub kernels: Vec<KernelModule>,
    /// Argument kernels of queued streams, by stream.
    pub args: BTreeMap<StreamId, KernelModule>,
    /// Commit kernels of each boundary: resetting and adding.
    pub commits: Vec<[KernelModule; 2]>,
    /// Kernels that zero a control word (or move it to the word a regeneration gate reads),
    /// by word.
    pub zeros: BTreeMap<u32, KernelModule>,
    /// The domain kernel of each phase counted on the GPU.
    pub domains: BTreeMap<PhaseId, KernelModule>,
    /// The kernels of each live operator.
    pub ops: Vec<OpModules>,
    /// The counter fold kernel.
    pub fold: KernelModule,
    /// The target compiled for.
    pub target: Target,
}

thread_local! {
    /// Programs compiled on this thread ([`compile`]), for [`compiles_on_this_thread`].
    static COMPILES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// How many programs [`compile`] has compiled on the calling thread: a test's count of the
/// compiles one front-end call makes (other threads' compiles do not count).
pub fn compiles_on_this_thread() -> u64 {
    COMPILES.with(|c| c.get())
}

/// The engine's compile entry: specialises `graph` to `spec` (the layout's constants where
/// `spec` does not give them; culling what the constants switch off), plans the layout `decl`
/// (called `layout` in errors) once on the live graph, reflects over the WGSL with naga,
/// resolves sizes and memory, and generates and validates every kernel for `target`. The
/// program holds its plan and resolved memory.
pub fn compile(
    graph: &Graph,
    layout: &str,
    decl: &LayoutDecl,
    spec: &Specialization,
    target: &Target,
) -> Result<Program> {
    COMPILES.with(|c| c.set(c.get() + 1));
    let mut constants = decl.constants.clone();
    constants.extend(spec.constants.iter().map(|(k, v)| (k.clone(), *v)));
    let live = graph.specialize_for(&constants, &spec.flags)?;
    let plan = Plan::with_decl(&live, layout, decl.clone())?;
    Program::generate(plan, spec, target)
}

impl Program {
    /// Reflects, resolves and generates the planned live graph `plan`.
    fn generate(plan: Plan, spec: &Specialization, target: &Target) -> Result<Program> {
        let shared = derive::sources(&plan.graph, &spec.flags)?;
        // Reflect: every source compiled together, with emits that do nothing.
        let begun = Resolved::for_reflection(&plan);
        let ctx = CodegenContext {
            plan: &plan,
            resolved: &begun,
            max_loop_iterations: target.max_loop_iterations,
            subgroup_appends: target.subgroups(),
            fair_shares: target.fair_shares,
        };
        let rmod = reflect::reflect(&plan, &shared, &ctx.prelude(), &ctx.stub_emits(), target.capabilities)?;
        // Resolve, then generate.
        let resolved = begun.complete(&plan, &rmod, target)?;
        let kernels = pass_kernels(&plan, &resolved, &shared, target)?;
        let internal = Internal {
            plan: &plan,
            resolved: &resolved,
            target,
        };
        Ok(Program {
            args: internal.args()?,
            commits: internal.commits()?,
            zeros: internal.zeros()?,
            domains: internal.domains()?,
            ops: internal.operators()?,
            fold: internal.fold()?,
            kernels,
            plan,
            resolved,
            target: target.clone(),
        })
    }

    /// Bytes of the engine-allocated buffers with transient buffers sharing memory.
    pub fn peak_bytes(&self) -> u64 {
        self.resolved.memory.peak_bytes()
    }

    /// Constants of the program.
    pub fn constants(&self) -> &BTreeMap<String, ConstValue> {
        &self.resolved.constants
    }
}

/// The pass kernels: prelude, shared sources and the kernel's own part, without the
/// functions the entry point never calls, validated.
fn pass_kernels(
    plan: &Plan,
    resolved: &Resolved,
    shared: &[(String, String)],
    target: &Target,
) -> Result<Vec<KernelModule>> {
    let ctx = CodegenContext {
        plan,
        resolved,
        max_loop_iterations: target.max_loop_iterations,
        subgroup_appends: target.subgroups(),
        fair_shares: target.fair_shares,
    };
    let prelude = ctx.prelude();
    let mut kernels = Vec::new();
    for k in plan.kernel_ids() {
        let kp = &plan.kernels[k];
        let mut src = ModuleSource::default();
        src.push("<generated prelude>", &prelude);
        for (f, text) in shared {
            src.push(f, text);
        }
        src.push(&format!("<generated kernel {}>", kp.name), &ctx.kernel(k));
        let name_error = |e| match e {
            Error::Shader(m) => Error::Shader(format!("kernel {} of layout '{}': {m}", kp.name, plan.layout_name)),
            other => other,
        };
        let src = src.shaken().map_err(name_error)?;
        let (module, info) = src.compile(target.capabilities).map_err(name_error)?;
        let uses = entry_uses(&module, &info, &resolved.bindings);
        kernels.push(KernelModule {
            name: kp.name.clone(),
            source: src,
            module,
            uses,
            checks: if plan.layout.loop_guards {
                RuntimeChecks::All
            } else {
                RuntimeChecks::NoLoopGuards
            },
        });
    }
    Ok(kernels)
}

/// Compiles the engine's own kernels and the operators'.
struct Internal<'a> {
    plan: &'a Plan,
    resolved: &'a Resolved,
    target: &'a Target,
}

impl Internal<'_> {
    fn binding(&self, b: &BufferRef) -> u32 {
        self.resolved.bindings[b]
    }

    /// A module of one generated file, its uses from the program's binding numbers.
    fn compile(&self, name: &str, wgsl: &str) -> Result<KernelModule> {
        let mut source = ModuleSource::default();
        source.push(&format!("<generated {name}>"), wgsl);
        let (module, info) = source.compile(self.target.capabilities)?;
        let uses = entry_uses(&module, &info, &self.resolved.bindings);
        Ok(KernelModule {
            name: name.to_string(),
            source,
            module,
            uses,
            checks: RuntimeChecks::None,
        })
    }

    /// Indirect-argument slots: queues, then boundaries, then counted phases.
    fn args_slot_of_boundary(&self, b: usize) -> u32 {
        (self.resolved.queue_capacity.len() + b) as u32
    }

    fn args(&self) -> Result<BTreeMap<StreamId, KernelModule>> {
        let mut out = BTreeMap::new();
        for (i, &q) in self.plan.queued_streams.iter().enumerate() {
            let name = format!("lg_args_{}", self.plan.graph.streams[q].name);
            let wgsl = ArgsKernel {
                name: &name,
                control_binding: self.binding(&BufferRef::Control),
                args_binding: self.binding(&BufferRef::Args),
                count_word: self.resolved.control.queue_count[&q],
                append_word: self.resolved.control.queue_append[&q],
                capacity: self.resolved.queue_capacity[&q],
                args_offset: 3 * i as u32,
                workgroup: self.plan.layout.workgroup_size,
                max_groups: self.target.max_workgroups_per_dimension,
            }
            .wgsl();
            out.insert(q, self.compile(&name, &wgsl)?);
        }
        Ok(out)
    }

    fn commits(&self) -> Result<Vec<[KernelModule; 2]>> {
        let mut out = Vec::new();
        for b in 0..self.plan.boundaries.len() {
            let mut modes = Vec::new();
            for add in [false, true] {
                let name = format!("lg_commit_{b}_{}", if add { "add" } else { "reset" });
                let wgsl = CommitKernel {
                    name: &name,
                    boundary_binding: self.binding(&BufferRef::BoundaryIn),
                    args_binding: self.binding(&BufferRef::Args),
                    args_offset: 3 * self.args_slot_of_boundary(b),
                    workgroup: self.plan.layout.workgroup_size,
                    max_groups: self.target.max_workgroups_per_dimension,
                    add,
                }
                .wgsl();
                modes.push(self.compile(&name, &wgsl)?);
            }
            let [reset, add]: [KernelModule; 2] = modes.try_into().expect("two modes");
            out.push([reset, add]);
        }
        Ok(out)
    }

    fn zeros(&self) -> Result<BTreeMap<u32, KernelModule>> {
        let control = &self.resolved.control;
        let mut out = BTreeMap::new();
        for &word in control.alive.values().chain(control.next.values()) {
            let name = format!("lg_zero_{word}");
            let binding = self.binding(&BufferRef::Control);
            // An alive count a regeneration gate reads moves to its held word instead.
            let held = control
                .alive
                .iter()
                .find(|&(_, &w)| w == word)
                .and_then(|(c, _)| control.held.get(c));
            let wgsl = match held {
                Some(&to) => roll_kernel(&name, binding, word, to),
                None => zero_kernel(&name, binding, word),
            };
            out.insert(word, self.compile(&name, &wgsl)?);
        }
        Ok(out)
    }

    fn domains(&self) -> Result<BTreeMap<PhaseId, KernelModule>> {
        let g = &self.plan.graph;
        let first_slot = self.resolved.queue_capacity.len() + self.plan.boundaries.len();
        let mut out = BTreeMap::new();
        for (i, (&ph, &word)) in self.resolved.control.domain.iter().enumerate() {
            let counter = g.phase_domain(ph).counted.expect("counted phases have a counter");
            let name = format!("lg_domain_{ph}");
            let wgsl = DomainKernel {
                name: &name,
                counter_binding: self.binding(&BufferRef::Resource(counter)),
                control_binding: self.binding(&BufferRef::Control),
                args_binding: self.binding(&BufferRef::Args),
                word,
                args_offset: 3 * (first_slot + i) as u32,
                workgroup: self.plan.layout.workgroup_size,
                max_groups: self.target.max_workgroups_per_dimension,
            }
            .wgsl();
            out.insert(ph, self.compile(&name, &wgsl)?);
        }
        Ok(out)
    }

    fn operators(&self) -> Result<Vec<OpModules>> {
        let g = &self.plan.graph;
        let mut out = Vec::new();
        for (o, op) in g.ops.iter().enumerate() {
            let mut kernels = Vec::new();
            for k in op_kernels(g, OpId(o), self.resolved, self.target) {
                let mut source = ModuleSource::default();
                source.push(&format!("<generated operator '{}'>", op.name), &k.wgsl);
                let (module, _) = source.compile(self.target.capabilities)?;
                let mut uses: Vec<BindingUse> = k
                    .bindings
                    .iter()
                    .map(|(binding, buffer)| BindingUse {
                        buffer: buffer.clone(),
                        binding: *binding,
                        read_only: false,
                        uniform: false,
                    })
                    .collect();
                uses.push(BindingUse::frame());
                let module = KernelModule {
                    name: k.name,
                    source,
                    module,
                    uses,
                    checks: RuntimeChecks::None,
                };
                kernels.push((module, k.groups));
            }
            out.push(OpModules { kernels });
        }
        Ok(out)
    }

    fn fold(&self) -> Result<KernelModule> {
        let wgsl = fold_kernel(
            self.binding(&BufferRef::Counters),
            self.binding(&BufferRef::Totals),
            self.plan.graph.counters.len(),
        );
        self.compile("lg_fold", &wgsl)
    }
}

impl BindingUse {
    /// The frame record (group 1).
    pub fn frame() -> BindingUse {
        BindingUse {
            buffer: BufferRef::Frame,
            binding: 0,
            read_only: true,
            uniform: true,
        }
    }
}

/// The buffers the module's (single) entry point uses, from naga's analysis: group 0's by
/// the program's binding numbers, and the frame record (group 1).
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
        if rb.group == 1 {
            out.push(BindingUse::frame());
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
