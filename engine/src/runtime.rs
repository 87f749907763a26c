//! Running a compiled program on a GPU: buffers, pipelines, and frames made of dispatches
//! (direct, indirect from queue counters, and host-driven loops), with GPU timestamps and
//! counters read back once per frame.

use crate::codegen::BufferRef;
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::ir::Scope;
use crate::plan::Step;
use crate::program::{BindingUse, Program, entry_uses};
use crate::wgsl::ModuleSource;
use std::borrow::Cow;
use std::collections::BTreeMap;

const RECORD_STRIDE: u64 = 256;
const MAX_QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;
/// Host loop iterations after which a loop is declared stuck.
const MAX_HOST_ITERATIONS: u32 = 1 << 20;

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

struct Kernel {
    name: String,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Whether it reads the frame record (bound with a dynamic offset).
    uses_frame: bool,
}

/// A program instantiated on a GPU, ready to run frames.
pub struct Instance<'g> {
    gpu: &'g Gpu,
    program: Program,
    buffers: BTreeMap<BufferRef, wgpu::Buffer>,
    external_counts: BTreeMap<String, u64>,
    kernels: Vec<Kernel>,
    args: BTreeMap<String, (Kernel, u64)>,
    fold: Kernel,
    frame_records: wgpu::Buffer,
    records: Vec<[u32; 4]>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    readback: wgpu::Buffer,
    totals: Vec<u64>,
}

struct Recorder {
    encoder: wgpu::CommandEncoder,
    /// Kernel index of each timestamp pair written so far.
    timed: Vec<usize>,
    host_iterations: u32,
}

fn compile_internal(source: &str, name: &str, program: &Program) -> Result<(naga::Module, Vec<BindingUse>)> {
    let mut src = ModuleSource::default();
    src.push(&format!("<generated {name}>"), source);
    let (module, info) = src.compile(program.target.capabilities)?;
    let uses = entry_uses(&module, &info, &program.bindings);
    Ok((module, uses))
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
                    "{label} needs {:.1} MiB but the adapter binds at most {:.1} MiB per storage buffer; use fewer items per frame (or max_items_in_flight)",
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
        let ncounters = g.counters.len() as u64;
        buffers.insert(BufferRef::Counters, make("counters", 4 * ncounters, storage)?);
        buffers.insert(BufferRef::Totals, make("counter totals", 8 * ncounters, storage)?);
        buffers.insert(
            BufferRef::Control,
            make("control words", 4 * program.control.len as u64, storage)?,
        );
        buffers.insert(
            BufferRef::Args,
            make(
                "indirect arguments",
                12 * program.queue_capacity.len() as u64,
                storage | wgpu::BufferUsages::INDIRECT,
            )?,
        );
        let nrecords: u64 = program
            .domains
            .iter()
            .zip(&program.chunks)
            .map(|(d, c)| d.div_ceil(*c).max(1))
            .sum();
        let frame_records = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame records"),
            size: nrecords * RECORD_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let build = |name: &str,
                     module: naga::Module,
                     uses: &[BindingUse],
                     buffers: &BTreeMap<BufferRef, wgpu::Buffer>|
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
            let bg_entries: Vec<wgpu::BindGroupEntry> = uses
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
                        buffers[&u.buffer].as_entire_binding()
                    },
                })
                .collect();
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(name),
                layout: &bgl,
                entries: &bg_entries,
            });
            Kernel {
                name: name.to_string(),
                pipeline,
                bind_group,
                uses_frame: uses.iter().any(|u| u.uniform),
            }
        };

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut kernels = Vec::new();
        for km in &program.kernels {
            kernels.push(build(&km.name, km.module.clone(), &km.uses, &buffers));
        }
        let mut args = BTreeMap::new();
        for (i, (q, wgsl)) in program.args_kernels.iter().enumerate() {
            let name = format!("lg_args_{q}");
            let (module, uses) = compile_internal(wgsl, &name, &program)?;
            args.insert(q.clone(), (build(&name, module, &uses, &buffers), 12 * i as u64));
        }
        let (fold_module, fold_uses) = compile_internal(&program.fold_kernel, "lg_fold", &program)?;
        let fold = build("lg_fold", fold_module, &fold_uses, &buffers);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "creating the pipelines of layout '{}' failed: {e}",
                program.plan.layout_name
            )));
        }

        let queries = gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY).then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_QUERIES,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 8 * MAX_QUERIES as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (4 * program.control.len as u64 + 8 * ncounters + 8 * MAX_QUERIES as u64).next_multiple_of(8),
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
            fold,
            frame_records,
            records: Vec::new(),
            queries,
            readback,
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
        let ts = match (&self.queries, timed) {
            (Some((set, _)), Some(ki)) if (rec.timed.len() as u32 + 1) * 2 <= MAX_QUERIES => {
                let i = rec.timed.len() as u32 * 2;
                rec.timed.push(ki);
                Some(wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(i),
                    end_of_pass_write_index: Some(i + 1),
                })
            }
            _ => None,
        };
        let mut pass = rec.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&k.name),
            timestamp_writes: ts,
        });
        pass.set_pipeline(&k.pipeline);
        let offset = [(record as u64 * RECORD_STRIDE) as u32];
        pass.set_bind_group(0, &k.bind_group, if k.uses_frame { &offset[..] } else { &[] });
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
    }

    fn run_steps(&self, rec: &mut Recorder, steps: &[Step], record: usize) -> Result<()> {
        let count = self.records[record][3] as u64;
        for step in steps {
            match step {
                Step::Run(k) => self.dispatch(rec, &self.kernels[*k], Some(*k), record, Dispatch::Items(count)),
                Step::Drain(q) => {
                    let (args, offset) = &self.args[q];
                    self.dispatch(rec, args, None, record, Dispatch::Single);
                    let k = self.program.plan.consumer_kernel(q);
                    self.dispatch(rec, &self.kernels[k], Some(k), record, Dispatch::Indirect(*offset));
                    let word = self.program.control.queue_count[q] as u64;
                    rec.encoder
                        .clear_buffer(&self.buffers[&BufferRef::Control], 4 * word, Some(4));
                }
                Step::Loop { chain, body } => {
                    let word = self.program.control.alive[chain] as u64;
                    let mut batch = 2u32;
                    let mut done = 0u32;
                    loop {
                        for _ in 0..batch {
                            rec.encoder
                                .clear_buffer(&self.buffers[&BufferRef::Control], 4 * word, Some(4));
                            self.run_steps(rec, body, record)?;
                        }
                        done += batch;
                        rec.host_iterations += batch;
                        let alive = self.read_control_word(rec, word)?;
                        if alive == 0 {
                            break;
                        }
                        if done >= MAX_HOST_ITERATIONS {
                            let item = &self.program.plan.graph.chains[*chain].item;
                            return Err(Error::Runtime(format!(
                                "{alive} items of '{item}' still alive after {done} loop iterations: a loop pass never finishes its item"
                            )));
                        }
                        batch = (batch * 2).min(32);
                    }
                }
            }
        }
        Ok(())
    }

    /// Submits what is recorded, then reads one control word.
    fn read_control_word(&self, rec: &mut Recorder, word: u64) -> Result<u32> {
        rec.encoder
            .copy_buffer_to_buffer(&self.buffers[&BufferRef::Control], 4 * word, &self.readback, 0, 4);
        let encoder = std::mem::replace(
            &mut rec.encoder,
            self.gpu.device.create_command_encoder(&Default::default()),
        );
        self.gpu.queue.submit([encoder.finish()]);
        let bytes = self.map_readback(8)?;
        Ok(u32::from_le_bytes(bytes[0..4].try_into().expect("4 bytes")))
    }

    fn map_readback(&self, size: u64) -> Result<Vec<u8>> {
        let slice = self.readback.slice(0..size);
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
        let program = &self.program;
        self.records.clear();
        let mut plan_records = Vec::new();
        for (ph, (&domain, &chunk)) in program.domains.iter().zip(&program.chunks).enumerate() {
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
        let mut bytes = vec![0u8; self.records.len() * RECORD_STRIDE as usize];
        for (i, r) in self.records.iter().enumerate() {
            bytes[i * RECORD_STRIDE as usize..][..16].copy_from_slice(bytemuck::cast_slice(r));
        }
        self.gpu.queue.write_buffer(&self.frame_records, 0, &bytes);
        let scope = self.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut rec = Recorder {
            encoder: self.gpu.device.create_command_encoder(&Default::default()),
            timed: Vec::new(),
            host_iterations: 0,
        };
        rec.encoder.clear_buffer(&self.buffers[&BufferRef::Control], 0, None);
        for (ph, record) in plan_records {
            self.run_steps(&mut rec, &self.program.plan.schedule[ph], record)?;
            self.dispatch(&mut rec, &self.fold, None, record, Dispatch::Single);
        }
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
        let nq = 2 * rec.timed.len() as u32;
        if let (Some((set, resolve)), true) = (&self.queries, nq > 0) {
            rec.encoder.resolve_query_set(set, 0..nq, resolve, 0);
            rec.encoder
                .copy_buffer_to_buffer(resolve, 0, &self.readback, ts_at, 8 * nq as u64);
        }
        self.gpu.queue.submit([rec.encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("running a frame failed: {e}")));
        }
        let data = self.map_readback(ts_at + 8 * nq as u64)?;
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
        if nq > 0 {
            let period = self.gpu.queue.get_timestamp_period() as f64 * 1e-9;
            let ticks: &[u64] = bytemuck::cast_slice(&data[ts_at as usize..(ts_at + 8 * nq as u64) as usize]);
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
