//! Running a compiled program on a GPU: buffers, pipelines, and frames made of dispatches
//! (direct, indirect from queue and boundary counters, and host-driven loops), with GPU
//! timestamps and counters read back once per frame.

use crate::codegen::{BufferRef, CommitKernel};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::ir::Scope;
use crate::plan::{Port, Root, Side, Step};
use crate::program::{BindingUse, Program, entry_uses};
use crate::wgsl::ModuleSource;
use std::borrow::Cow;
use std::collections::BTreeMap;

const RECORD_STRIDE: u64 = 256;
/// Most frames [`Instance::run_frames`] records together.
pub const MAX_BATCH: u32 = 64;
const MAX_QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;
/// Timestamp pairs in the query set.
const QUERY_PAIRS: usize = MAX_QUERIES as usize / 2;
/// Timestamp pairs a batch can resolve; later dispatches go untimed.
const MAX_TIMED: usize = 16 * QUERY_PAIRS;
/// Host loop iterations after which a loop is declared stuck.
const MAX_HOST_ITERATIONS: u32 = 1 << 20;
/// Bytes of a boundary buffer's header (count, append, two spare words).
const BOUNDARY_HEADER: u64 = 16;

/// Statistics of one frame.
#[derive(Debug, Clone, Default)]
pub struct FrameStats {
    /// Counter increments during the frame, by counter name.
    pub counters: BTreeMap<String, u64>,
    /// GPU time of each kernel during the frame, in seconds, by kernel name (empty when
    /// the device has no timestamp queries).
    pub kernel_seconds: BTreeMap<String, f64>,
    /// Host-driven loop iterations run.
    pub host_iterations: u32,
    /// In-kernel loops stopped by the iteration cap (a pass that never finished its item).
    pub loops_capped: u32,
}

impl FrameStats {
    /// Total GPU time of the frame's kernels.
    pub fn gpu_seconds(&self) -> f64 {
        self.kernel_seconds.values().sum()
    }
}

/// A pipeline with its bind groups: one, or one per iteration parity for kernels that use a
/// ping-pong boundary.
struct Kernel {
    name: String,
    pipeline: wgpu::ComputePipeline,
    bind_groups: Vec<wgpu::BindGroup>,
    /// Whether it reads the frame record (bound with a dynamic offset).
    uses_frame: bool,
}

/// Maps a kernel's virtual boundary bindings to physical buffers.
type Resolve = Box<dyn Fn(&BufferRef) -> BufferRef>;

/// A program instantiated on a GPU, ready to run frames.
pub struct Instance<'g> {
    gpu: &'g Gpu,
    program: Program,
    buffers: BTreeMap<BufferRef, wgpu::Buffer>,
    external_counts: BTreeMap<String, u64>,
    kernels: Vec<Kernel>,
    /// Argument kernels of queued streams, with the byte offset of their arguments.
    args: BTreeMap<String, (Kernel, u64)>,
    /// Commit kernels of boundaries, resetting and adding (one bind group per physical
    /// buffer), with the byte offset of their arguments.
    commits: Vec<([Kernel; 2], u64)>,
    /// Kernels that zero a control word, by word.
    zeros: BTreeMap<u32, Kernel>,
    fold: Kernel,
    frame_records: wgpu::Buffer,
    records: Vec<[u32; 4]>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    readback: wgpu::Buffer,
    totals: Vec<u64>,
    /// Host loop iterations the previous frame needed, per loop (the next frame's first batch).
    last_iterations: BTreeMap<usize, u32>,
}

/// Commands of a batch being recorded: one compute pass stays open across dispatches until an
/// encoder-level command (a copy, a query resolve, a submission) needs it closed.
struct Recorder {
    encoder: wgpu::CommandEncoder,
    pass: Option<wgpu::ComputePass<'static>>,
    /// Kernel index of each timestamp pair written so far in the batch.
    timed: Vec<usize>,
    /// Timestamp pairs already resolved into the resolve buffer.
    resolved: usize,
    host_iterations: u32,
    /// Iteration parity of the running host loop (selects ping-pong buffers).
    parity: usize,
}

impl Recorder {
    fn new(device: &wgpu::Device) -> Recorder {
        Recorder {
            encoder: device.create_command_encoder(&Default::default()),
            pass: None,
            timed: Vec::new(),
            resolved: 0,
            host_iterations: 0,
            parity: 0,
        }
    }

    fn pass(&mut self) -> &mut wgpu::ComputePass<'static> {
        if self.pass.is_none() {
            let pass = self.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("lightgraph"),
                timestamp_writes: None,
            });
            self.pass = Some(pass.forget_lifetime());
        }
        self.pass.as_mut().expect("just opened")
    }

    fn end_pass(&mut self) {
        self.pass = None;
    }

    /// Ends the pass and resolves the timestamps written since the last resolve.
    fn resolve(&mut self, queries: &Option<(wgpu::QuerySet, wgpu::Buffer)>) {
        self.end_pass();
        if let Some((set, buffer)) = queries {
            let pairs = self.timed.len() - self.resolved;
            if pairs > 0 {
                let first = (self.resolved % QUERY_PAIRS) as u32 * 2;
                self.encoder
                    .resolve_query_set(set, first..first + 2 * pairs as u32, buffer, 16 * self.resolved as u64);
                self.resolved = self.timed.len();
            }
        }
    }
}

fn compile_internal(source: &str, name: &str, program: &Program) -> Result<(naga::Module, Vec<BindingUse>)> {
    let mut src = ModuleSource::default();
    src.push(&format!("<generated {name}>"), source);
    let (module, info) = src.compile(program.target.capabilities)?;
    let uses = entry_uses(&module, &info, &program.bindings);
    Ok((module, uses))
}

/// The physical buffer of a boundary port in iteration `parity`.
fn physical(program: &Program, port: Port, parity: usize) -> BufferRef {
    let side = if program.plan.boundaries[port.boundary].pingpong {
        (parity + (port.side == Side::Next) as usize) % 2
    } else {
        0
    };
    BufferRef::Boundary(port.boundary, side)
}

impl<'g> Instance<'g> {
    /// Creates buffers and pipelines. `externals` supplies the bytes of every external
    /// resource.
    pub fn new(gpu: &'g Gpu, program: Program, externals: &BTreeMap<String, Vec<u8>>) -> Result<Instance<'g>> {
        let g = &program.plan.graph;
        let device = &gpu.device;
        let max_binding = gpu.limits.max_storage_buffer_binding_size;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let mut buffers = BTreeMap::new();
        let mut external_counts = BTreeMap::new();
        let make = |label: &str, size: u64, usage: wgpu::BufferUsages| -> Result<wgpu::Buffer> {
            let size = size.max(16).next_multiple_of(4);
            if usage.contains(wgpu::BufferUsages::STORAGE) && size > max_binding {
                return Err(Error::Gpu(format!(
                    "{label} needs {:.1} MiB but the adapter binds at most {:.1} MiB per storage buffer; use fewer items per frame (or max_items_in_flight, threads)",
                    size as f64 / 1048576.0,
                    max_binding as f64 / 1048576.0
                )));
            }
            Ok(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            }))
        };
        for name in externals.keys() {
            if g.resources.get(name).is_none_or(|r| r.scope != Scope::External) {
                return Err(Error::Runtime(format!(
                    "data given for '{name}', which graph '{}' has no external resource of that name",
                    g.name
                )));
            }
        }
        for (name, r) in &g.resources {
            let elem = program.sizes[name].element_bytes as u64;
            let buf = if r.scope == Scope::External {
                let bytes = externals.get(name).ok_or_else(|| {
                    Error::Runtime(format!(
                        "graph '{}' needs external resource '{name}' ({}), which was not supplied",
                        g.name, r.ty
                    ))
                })?;
                if !(bytes.len() as u64).is_multiple_of(elem) {
                    return Err(Error::Runtime(format!(
                        "external resource '{name}': {} bytes is not a whole number of {elem}-byte '{}' elements",
                        bytes.len(),
                        r.ty
                    )));
                }
                external_counts.insert(name.clone(), bytes.len() as u64 / elem);
                let b = make(&format!("resource '{name}'"), (bytes.len() as u64).max(elem), storage)?;
                gpu.queue.write_buffer(&b, 0, bytes);
                b
            } else {
                make(
                    &format!("resource '{name}'"),
                    elem * program.sizes[name].count.unwrap_or(1),
                    storage,
                )?
            };
            buffers.insert(BufferRef::Resource(name.clone()), buf);
        }
        for (&c, &cap) in &program.state_capacity {
            let words = program.words[&g.chains[c].item].len() as u64;
            buffers.insert(
                BufferRef::State(c),
                make(&format!("state of chain {c}"), 4 * words * cap, storage)?,
            );
            buffers.insert(
                BufferRef::Alive(c),
                make(&format!("alive flags of chain {c}"), 4 * cap, storage)?,
            );
        }
        for (q, &cap) in &program.queue_capacity {
            let words = program.words[&g.streams[q].item].len() as u64;
            buffers.insert(
                BufferRef::Queue(q.clone()),
                make(&format!("queue '{q}'"), 4 * words * cap, storage)?,
            );
        }
        for (b, boundary) in program.plan.boundaries.iter().enumerate() {
            let words = program.words[&g.chains[boundary.chain].item].len() as u64;
            let size = BOUNDARY_HEADER + 4 * words * program.pools[&boundary.chain];
            for side in 0..1 + boundary.pingpong as usize {
                buffers.insert(
                    BufferRef::Boundary(b, side),
                    make(&format!("boundary {b}.{side}"), size, storage)?,
                );
            }
        }
        let ncounters = g.counters.len() as u64;
        buffers.insert(BufferRef::Counters, make("counters", 4 * ncounters, storage)?);
        buffers.insert(BufferRef::Totals, make("counter totals", 8 * ncounters, storage)?);
        buffers.insert(
            BufferRef::Control,
            make("control words", 4 * program.control.len as u64, storage)?,
        );
        let nargs = (program.queue_capacity.len() + program.plan.boundaries.len()) as u64;
        buffers.insert(
            BufferRef::Args,
            make("indirect arguments", 12 * nargs, storage | wgpu::BufferUsages::INDIRECT)?,
        );
        let nrecords: u64 = MAX_BATCH as u64
            * program
                .domains
                .iter()
                .zip(&program.chunks)
                .map(|(d, c)| d.div_ceil(*c).max(1))
                .sum::<u64>();
        let frame_records = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame records"),
            size: nrecords * RECORD_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        // A pipeline and one bind group per entry of `resolves`, which maps the virtual
        // boundary bindings to physical buffers.
        let build = |name: &str,
                     module: naga::Module,
                     uses: &[BindingUse],
                     resolves: &[&dyn Fn(&BufferRef) -> BufferRef]|
         -> Kernel {
            let entries: Vec<wgpu::BindGroupLayoutEntry> = uses
                .iter()
                .map(|u| wgpu::BindGroupLayoutEntry {
                    binding: u.binding,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: if u.uniform {
                            wgpu::BufferBindingType::Uniform
                        } else {
                            wgpu::BufferBindingType::Storage { read_only: u.read_only }
                        },
                        has_dynamic_offset: u.uniform,
                        min_binding_size: None,
                    },
                    count: None,
                })
                .collect();
            let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(name),
                entries: &entries,
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(name),
                bind_group_layouts: &[Some(&bgl)],
                immediate_size: 0,
            });
            let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Naga(Cow::Owned(module)),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                module: &shader,
                entry_point: Some(name),
                compilation_options: Default::default(),
                cache: None,
            });
            let bind_groups = resolves
                .iter()
                .map(|resolve| {
                    let entries: Vec<wgpu::BindGroupEntry> = uses
                        .iter()
                        .map(|u| wgpu::BindGroupEntry {
                            binding: u.binding,
                            resource: if u.uniform {
                                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                    buffer: &frame_records,
                                    offset: 0,
                                    size: wgpu::BufferSize::new(16),
                                })
                            } else {
                                buffers[&resolve(&u.buffer)].as_entire_binding()
                            },
                        })
                        .collect();
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(name),
                        layout: &bgl,
                        entries: &entries,
                    })
                })
                .collect();
            Kernel {
                name: name.to_string(),
                pipeline,
                bind_groups,
                uses_frame: uses.iter().any(|u| u.uniform),
            }
        };
        let identity = |b: &BufferRef| b.clone();

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut kernels = Vec::new();
        for (km, kp) in program.kernels.iter().zip(&program.plan.kernels) {
            let resolve = |parity: usize| {
                let (input, output) = (kp.input, kp.output);
                let program = &program;
                move |b: &BufferRef| match b {
                    BufferRef::BoundaryIn => physical(program, input.expect("reads a boundary"), parity),
                    BufferRef::BoundaryOut => physical(program, output.expect("writes a boundary"), parity),
                    other => other.clone(),
                }
            };
            let (even, odd) = (resolve(0), resolve(1));
            kernels.push(build(&km.name, km.module.clone(), &km.uses, &[&even, &odd]));
        }
        let mut args = BTreeMap::new();
        for (i, (q, wgsl)) in program.args_kernels.iter().enumerate() {
            let name = format!("lg_args_{q}");
            let (module, uses) = compile_internal(wgsl, &name, &program)?;
            args.insert(q.clone(), (build(&name, module, &uses, &[&identity]), 12 * i as u64));
        }
        let mut commits = Vec::new();
        for (b, boundary) in program.plan.boundaries.iter().enumerate() {
            let slot = program.queue_capacity.len() + b;
            let sides: Vec<Resolve> = (0..1 + boundary.pingpong as usize)
                .map(|side| {
                    Box::new(move |r: &BufferRef| {
                        if *r == BufferRef::BoundaryIn {
                            BufferRef::Boundary(b, side)
                        } else {
                            r.clone()
                        }
                    }) as Resolve
                })
                .collect();
            let refs: Vec<&dyn Fn(&BufferRef) -> BufferRef> = sides.iter().map(|f| f.as_ref()).collect();
            let mut modes = Vec::new();
            for add in [false, true] {
                let name = format!("lg_commit_{b}_{}", if add { "add" } else { "reset" });
                let wgsl = CommitKernel {
                    name: &name,
                    boundary_binding: program.bindings[&BufferRef::BoundaryIn],
                    args_binding: program.bindings[&BufferRef::Args],
                    args_offset: 3 * slot as u32,
                    workgroup: program.plan.layout.workgroup_size,
                    max_groups: program.target.max_workgroups_per_dimension,
                    add,
                }
                .wgsl();
                let (module, uses) = compile_internal(&wgsl, &name, &program)?;
                modes.push(build(&name, module, &uses, &refs));
            }
            let [reset, add]: [Kernel; 2] = modes
                .try_into()
                .map_err(|_| Error::Runtime("two commit modes".into()))?;
            commits.push(([reset, add], 12 * slot as u64));
        }
        let mut zeros = BTreeMap::new();
        let words = program.control.alive.values().chain(program.control.next.values());
        for &word in words {
            let name = format!("lg_zero_{word}");
            let control = program.bindings[&BufferRef::Control];
            // An alive count a regeneration gate reads moves to its held word instead.
            let held = program
                .control
                .alive
                .iter()
                .find(|&(_, &w)| w == word)
                .and_then(|(c, _)| program.control.held.get(c));
            let wgsl = match held {
                Some(&to) => crate::codegen::roll_kernel(&name, control, word, to),
                None => crate::codegen::zero_kernel(&name, control, word),
            };
            let (module, uses) = compile_internal(&wgsl, &name, &program)?;
            zeros.insert(word, build(&name, module, &uses, &[&identity]));
        }
        let (fold_module, fold_uses) = compile_internal(&program.fold_kernel, "lg_fold", &program)?;
        let fold = build("lg_fold", fold_module, &fold_uses, &[&identity]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the pipelines of layout '{}' failed: {e}",
                program.plan.layout_name
            )));
        }

        let timing = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES;
        let queries = gpu.features.contains(timing).then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_QUERIES,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 16 * MAX_TIMED as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        let readback_words = program.control.len as u64 + 4 * program.plan.boundaries.len() as u64 * 2;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (4 * readback_words + 8 * ncounters + 16 * MAX_TIMED as u64).next_multiple_of(8),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Instance {
            gpu,
            totals: vec![0; g.counters.len()],
            program,
            buffers,
            external_counts,
            kernels,
            args,
            commits,
            zeros,
            fold,
            frame_records,
            records: Vec::new(),
            queries,
            readback,
            last_iterations: BTreeMap::new(),
        })
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Element count of an external resource, as supplied.
    pub fn external_count(&self, name: &str) -> Option<u64> {
        self.external_counts.get(name).copied()
    }

    fn dispatch(&self, rec: &mut Recorder, k: &Kernel, timed: Option<usize>, record: usize, groups: Dispatch) {
        let query = match (&self.queries, timed) {
            (Some(_), Some(ki)) if rec.timed.len() < MAX_TIMED => {
                if rec.timed.len() > rec.resolved && rec.timed.len().is_multiple_of(QUERY_PAIRS) {
                    // The query set is full: resolve it before its queries are written again.
                    rec.resolve(&self.queries);
                }
                let i = (rec.timed.len() % QUERY_PAIRS) as u32 * 2;
                rec.timed.push(ki);
                Some(i)
            }
            _ => None,
        };
        let offset = [(record as u64 * RECORD_STRIDE) as u32];
        let bind_group = &k.bind_groups[rec.parity % k.bind_groups.len()];
        let set = self.queries.as_ref().map(|(set, _)| set);
        let pass = rec.pass();
        if let (Some(i), Some(set)) = (query, set) {
            pass.write_timestamp(set, i);
        }
        pass.set_pipeline(&k.pipeline);
        pass.set_bind_group(0, bind_group, if k.uses_frame { &offset[..] } else { &[] });
        match groups {
            Dispatch::Items(n) => {
                let wg = self.program.plan.layout.workgroup_size as u64;
                let groups = n.div_ceil(wg);
                if groups > 0 {
                    let max = self.program.target.max_workgroups_per_dimension as u64;
                    let x = groups.min(max);
                    pass.dispatch_workgroups(x as u32, groups.div_ceil(x) as u32, 1);
                }
            }
            Dispatch::Indirect(offset) => pass.dispatch_workgroups_indirect(&self.buffers[&BufferRef::Args], offset),
            Dispatch::Single => pass.dispatch_workgroups(1, 1, 1),
        }
        if let (Some(i), Some(set)) = (query, set) {
            pass.write_timestamp(set, i + 1);
        }
    }

    /// Commits a boundary buffer (its appended items become, or with `add` join, its count)
    /// and prepares the indirect arguments for its consumer; returns their offset.
    fn commit(&self, rec: &mut Recorder, port: Port, record: usize, add: bool) -> u64 {
        let (kernels, offset) = &self.commits[port.boundary];
        let side = match physical(&self.program, port, rec.parity) {
            BufferRef::Boundary(_, side) => side,
            _ => unreachable!("boundary ports map to boundary buffers"),
        };
        let saved = rec.parity;
        rec.parity = side;
        self.dispatch(rec, &kernels[add as usize], None, record, Dispatch::Single);
        rec.parity = saved;
        *offset
    }

    fn run_kernel(&self, rec: &mut Recorder, k: usize, record: usize) {
        let plan = &self.program.plan;
        let kp = &plan.kernels[k];
        let count = match self.program.pools.get(&kp.chain) {
            Some(&pool) => pool,
            None => self.records[record][3] as u64,
        };
        let kernel = &self.kernels[k];
        match (kp.input, kp.output) {
            (Some(input), _) => {
                // Items a pure regeneration kernel just appended join the survivors counted
                // before it; otherwise the last count was consumed and is replaced.
                let after_regeneration = plan.kernels.iter().any(|r| {
                    r.input.is_none() && r.output.map(|o| o.boundary) == Some(input.boundary) && r.root == Root::Start
                });
                let offset = self.commit(rec, input, record, after_regeneration);
                let groups = if kp.root == Root::Boundary {
                    Dispatch::Indirect(offset)
                } else {
                    Dispatch::Items(count)
                };
                self.dispatch(rec, kernel, Some(k), record, groups);
            }
            (None, Some(output)) => {
                self.commit(rec, output, record, false);
                self.dispatch(rec, kernel, Some(k), record, Dispatch::Items(count));
            }
            (None, None) => self.dispatch(rec, kernel, Some(k), record, Dispatch::Items(count)),
        }
    }

    fn run_steps(&mut self, rec: &mut Recorder, steps: &[Step], record: usize) -> Result<()> {
        for (i, step) in steps.iter().enumerate() {
            match step {
                Step::Run(k) => self.run_kernel(rec, *k, record),
                Step::Drain(q) => {
                    let (args, offset) = &self.args[q];
                    self.dispatch(rec, args, None, record, Dispatch::Single);
                    let k = self.program.plan.consumer_kernel(q);
                    self.dispatch(rec, &self.kernels[k], Some(k), record, Dispatch::Indirect(*offset));
                }
                Step::Loop { chain, body } => {
                    // The same loop of every frame of a batch learns from the last one.
                    let per_frame = self.records.iter().filter(|r| r[0] == self.records[0][0]).count();
                    let key = (record % per_frame.max(1)) * 64 + i;
                    let mut batch = self.last_iterations.get(&key).copied().unwrap_or(2).max(1);
                    let mut done = 0u32;
                    rec.parity = 0;
                    loop {
                        for _ in 0..batch {
                            if let Some(word) = self.program.control.alive.get(chain) {
                                self.dispatch(rec, &self.zeros[word], None, record, Dispatch::Single);
                            }
                            self.run_steps(rec, body, record)?;
                            rec.parity ^= 1;
                        }
                        done += batch;
                        rec.host_iterations += batch;
                        if !self.loop_goes_on(rec, *chain, record)? {
                            break;
                        }
                        if done >= MAX_HOST_ITERATIONS {
                            let item = &self.program.plan.graph.chains[*chain].item;
                            return Err(Error::Runtime(format!(
                                "items of '{item}' still alive after {done} loop iterations: a loop pass never finishes its item"
                            )));
                        }
                        batch = (batch * 2).min(64);
                    }
                    self.last_iterations.insert(key, done);
                }
            }
        }
        Ok(())
    }

    /// Submits what is recorded and reads back whether the loop over `chain` has work left:
    /// items alive in slots, items appended to its boundaries, or indices not yet taken.
    fn loop_goes_on(&self, rec: &mut Recorder, chain: usize, record: usize) -> Result<bool> {
        rec.end_pass();
        let control_bytes = 4 * self.program.control.len as u64;
        rec.encoder
            .copy_buffer_to_buffer(&self.buffers[&BufferRef::Control], 0, &self.readback, 0, control_bytes);
        let mut at = control_bytes;
        let mut headers = Vec::new();
        for (b, boundary) in self.program.plan.boundaries.iter().enumerate() {
            if boundary.chain != chain {
                continue;
            }
            for side in 0..1 + boundary.pingpong as usize {
                rec.encoder.copy_buffer_to_buffer(
                    &self.buffers[&BufferRef::Boundary(b, side)],
                    0,
                    &self.readback,
                    at,
                    8,
                );
                headers.push(at);
                at += 8;
            }
        }
        let encoder = std::mem::replace(
            &mut rec.encoder,
            self.gpu.device.create_command_encoder(&Default::default()),
        );
        self.gpu.queue.submit([encoder.finish()]);
        let bytes = self.map_readback(at)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        let control = &self.program.control;
        let alive = control.alive.get(&chain).map_or(0, |&w| words[w as usize]);
        // Counts of consumed boundaries are stale; waiting items are the appended ones.
        let pending: u64 = headers.iter().map(|&h| words[h as usize / 4 + 1] as u64).sum();
        let untaken = control
            .next
            .get(&chain)
            .is_some_and(|&w| (words[w as usize] as u64) < self.records[record][3] as u64);
        Ok(alive > 0 || pending > 0 || untaken)
    }

    fn map_readback(&self, size: u64) -> Result<Vec<u8>> {
        let slice = self.readback.slice(0..size.next_multiple_of(8));
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait()?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapping the readback buffer failed: {e}")))?
            .to_vec();
        self.readback.unmap();
        Ok(data)
    }

    /// Runs frame `index` with `seed`: every phase over all its chunks.
    pub fn run_frame(&mut self, index: u32, seed: u32) -> Result<FrameStats> {
        self.run_frames(index, 1, seed)
    }

    /// Runs frames `first .. first + count` (at most [`MAX_BATCH`]) with `seed`, recorded
    /// together and read back once: the statistics are the batch's.
    pub fn run_frames(&mut self, first: u32, count: u32, seed: u32) -> Result<FrameStats> {
        if count == 0 || count > MAX_BATCH {
            return Err(Error::Runtime(format!(
                "a batch runs 1 to {MAX_BATCH} frames, not {count}"
            )));
        }
        self.records.clear();
        let mut plan_records = Vec::new();
        for index in first..first + count {
            for (ph, (&domain, &chunk)) in self.program.domains.iter().zip(&self.program.chunks).enumerate() {
                let mut base = 0u64;
                loop {
                    let n = chunk.min(domain - base);
                    plan_records.push((ph, self.records.len()));
                    self.records.push([index, seed, base as u32, n as u32]);
                    base += n;
                    if base >= domain {
                        break;
                    }
                }
            }
        }
        let mut bytes = vec![0u8; self.records.len() * RECORD_STRIDE as usize];
        for (i, r) in self.records.iter().enumerate() {
            bytes[i * RECORD_STRIDE as usize..][..16].copy_from_slice(bytemuck::cast_slice(r));
        }
        self.gpu.queue.write_buffer(&self.frame_records, 0, &bytes);
        let scope = self.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut rec = Recorder::new(&self.gpu.device);
        rec.encoder.clear_buffer(&self.buffers[&BufferRef::Control], 0, None);
        for (b, boundary) in self.program.plan.boundaries.iter().enumerate() {
            for side in 0..1 + boundary.pingpong as usize {
                rec.encoder
                    .clear_buffer(&self.buffers[&BufferRef::Boundary(b, side)], 0, Some(8));
            }
        }
        for (ph, record) in plan_records {
            let steps = self.program.plan.schedule[ph].clone();
            let next_words: Vec<u32> = self
                .program
                .plan
                .kernels
                .iter()
                .filter(|k| k.phase == ph && k.regenerates)
                .map(|k| self.program.control.next[&k.chain])
                .collect();
            for word in next_words {
                self.dispatch(&mut rec, &self.zeros[&word], None, record, Dispatch::Single);
            }
            self.run_steps(&mut rec, &steps, record)?;
            self.dispatch(&mut rec, &self.fold, None, record, Dispatch::Single);
        }
        rec.resolve(&self.queries);
        // Read back control words, counter totals and timestamps.
        let control_bytes = 4 * self.program.control.len as u64;
        let ncounters = self.totals.len() as u64;
        let totals_at = control_bytes.next_multiple_of(8);
        let ts_at = totals_at + 8 * ncounters;
        rec.encoder
            .copy_buffer_to_buffer(&self.buffers[&BufferRef::Control], 0, &self.readback, 0, control_bytes);
        if ncounters > 0 {
            rec.encoder.copy_buffer_to_buffer(
                &self.buffers[&BufferRef::Totals],
                0,
                &self.readback,
                totals_at,
                8 * ncounters,
            );
        }
        let pairs = rec.timed.len() as u64;
        if let (Some((_, resolve)), true) = (&self.queries, pairs > 0) {
            rec.encoder
                .copy_buffer_to_buffer(resolve, 0, &self.readback, ts_at, 16 * pairs);
        }
        self.gpu.queue.submit([rec.encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("running a frame failed: {e}")));
        }
        let data = self.map_readback(ts_at + 16 * pairs)?;
        let words: &[u32] = bytemuck::cast_slice(&data[..control_bytes as usize]);
        for (q, &w) in &self.program.control.queue_overflow {
            if words[w as usize] > 0 {
                return Err(Error::Runtime(format!(
                    "queue '{q}' overflowed by {} items: a pass emits more than the stream's per_call ({}) declares",
                    words[w as usize], self.program.plan.graph.streams[q].per_call
                )));
            }
        }
        let mut stats = FrameStats {
            host_iterations: rec.host_iterations,
            loops_capped: words[self.program.control.loop_capped as usize],
            ..Default::default()
        };
        let g = &self.program.plan.graph;
        for (i, name) in g.counters.iter().enumerate() {
            let at = (totals_at + 8 * i as u64) as usize;
            let lo = u32::from_le_bytes(data[at..at + 4].try_into().expect("4 bytes")) as u64;
            let hi = u32::from_le_bytes(data[at + 4..at + 8].try_into().expect("4 bytes")) as u64;
            let total = lo | (hi << 32);
            stats.counters.insert(name.clone(), total - self.totals[i]);
            self.totals[i] = total;
        }
        if pairs > 0 {
            let period = self.gpu.queue.get_timestamp_period() as f64 * 1e-9;
            let ticks: &[u64] = bytemuck::cast_slice(&data[ts_at as usize..(ts_at + 16 * pairs) as usize]);
            for (i, &k) in rec.timed.iter().enumerate() {
                let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period;
                *stats.kernel_seconds.entry(self.kernels[k].name.clone()).or_insert(0.0) += dt;
            }
        }
        Ok(stats)
    }

    /// Counter totals since the instance was created.
    pub fn counter_totals(&self) -> BTreeMap<String, u64> {
        self.program
            .plan
            .graph
            .counters
            .iter()
            .cloned()
            .zip(self.totals.iter().copied())
            .collect()
    }

    fn resource(&self, name: &str) -> Result<&wgpu::Buffer> {
        self.buffers.get(&BufferRef::Resource(name.to_string())).ok_or_else(|| {
            Error::Runtime(format!(
                "graph '{}' has no resource '{name}'",
                self.program.plan.graph.name
            ))
        })
    }

    /// Reads a resource's bytes back to the host.
    pub fn read(&self, name: &str) -> Result<Vec<u8>> {
        let buf = self.resource(name)?;
        let size = buf.size();
        let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resource readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buf, 0, &staging, 0, size);
        self.gpu.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait()?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapping '{name}' failed: {e}")))?
            .to_vec();
        let logical = match self.program.sizes[name].count {
            Some(c) => c * self.program.sizes[name].element_bytes as u64,
            None => self.external_counts[name] * self.program.sizes[name].element_bytes as u64,
        };
        Ok(data[..logical as usize].to_vec())
    }

    /// Overwrites a resource's bytes (from the start).
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        let buf = self.resource(name)?;
        if bytes.len() as u64 > buf.size() {
            return Err(Error::Runtime(format!(
                "{} bytes do not fit resource '{name}' ({} bytes)",
                bytes.len(),
                buf.size()
            )));
        }
        self.gpu.queue.write_buffer(buf, 0, bytes);
        Ok(())
    }

    /// Sets a resource to zero.
    pub fn clear(&self, name: &str) -> Result<()> {
        let buf = self.resource(name)?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(buf, 0, None);
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }
}

#[derive(Clone, Copy)]
enum Dispatch {
    Items(u64),
    Indirect(u64),
    Single,
}
