//! Running a compiled program on a GPU: buffers placed as the memory plan says (transient
//! buffers sharing arenas), pipelines, per-frame parameters, and frames made of dispatches
//! (direct, indirect from queue, boundary and GPU counters, and host-driven loops) with GPU
//! timestamps and counters read back once per batch of frames, while the next batch runs.

mod buffers;
mod frames;
mod pipelines;
mod recorder;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::ids::{PhaseId, ResourceId, StreamId};
use crate::ir::ConstValue;
use crate::program::Program;
use crate::resolve::BufferRef;
use buffers::{Buffers, Slot};
use pipelines::Kernel;
use std::collections::BTreeMap;

/// Most frames [`Instance::run_frames`] records together.
pub const MAX_BATCH: u32 = 64;

/// Most batches [`Instance::submit_frames`] keeps in flight before one is collected.
pub const IN_FLIGHT: usize = 2;

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

    /// Adds these counter increments and kernel times to running totals.
    pub fn add_to(&self, counters: &mut BTreeMap<String, u64>, kernel_seconds: &mut BTreeMap<String, f64>) {
        for (k, v) in &self.counters {
            *counters.entry(k.clone()).or_insert(0) += v;
        }
        for (k, v) in &self.kernel_seconds {
            *kernel_seconds.entry(k.clone()).or_insert(0.0) += v;
        }
    }

    /// Adds the statistics of `other` (frames run besides these) to these.
    pub fn add(&mut self, other: &FrameStats) {
        other.add_to(&mut self.counters, &mut self.kernel_seconds);
        self.host_iterations += other.host_iterations;
        self.loops_capped += other.loops_capped;
    }
}

/// Where a parameter's value comes from.
enum ParameterSource {
    /// The same value every frame.
    Fixed(ConstValue),
    /// A function of the frame index.
    Schedule(Box<dyn Fn(u32) -> ConstValue + Send + Sync>),
}

/// The pipelines of an instance.
struct Kernels {
    /// Pass kernels, in plan order.
    passes: Vec<Kernel>,
    /// Argument kernels of queued streams, with the byte offset of their arguments.
    args: BTreeMap<StreamId, (Kernel, u64)>,
    /// Commit kernels of boundaries, resetting and adding (one bind group per physical
    /// buffer), with the byte offset of their arguments.
    commits: Vec<([Kernel; 2], u64)>,
    /// Kernels that zero (or move) a control word, by word.
    zeros: BTreeMap<u32, Kernel>,
    /// Domain kernels of GPU-counted phases, with the byte offset of their arguments.
    domains: BTreeMap<PhaseId, (Kernel, u64)>,
    /// The kernels of each operator, with their workgroups.
    ops: Vec<Vec<(Kernel, crate::scan::Groups)>>,
    fold: Kernel,
    /// Names of the timed kernels, by timing slot.
    timed_names: Vec<String>,
    /// The layout of the frame record's group (group 1).
    frame_layout: wgpu::BindGroupLayout,
}

/// A program instantiated on a GPU, ready to run frames.
pub struct Instance<'g> {
    gpu: &'g Gpu,
    program: Program,
    buffers: Buffers,
    kernels: Kernels,
    parameters: BTreeMap<String, ParameterSource>,
    frames: frames::FrameState,
    /// GPU copies of resources taken by [`Instance::snapshot`].
    snapshots: BTreeMap<ResourceId, wgpu::Buffer>,
}

impl<'g> Instance<'g> {
    /// Creates buffers and pipelines. `externals` supplies the bytes of external resources;
    /// those no live pass uses may be left out.
    pub fn new(gpu: &'g Gpu, program: Program, externals: &BTreeMap<String, Vec<u8>>) -> Result<Instance<'g>> {
        let buffers = Buffers::new(gpu, &program, externals)?;
        let kernels = pipelines::build(gpu, &program, &buffers)?;
        let frames = frames::FrameState::new(gpu, &program, &kernels.frame_layout);
        Ok(Instance {
            gpu,
            program,
            buffers,
            kernels,
            parameters: BTreeMap::new(),
            frames,
            snapshots: BTreeMap::new(),
        })
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Element count of an external resource, as supplied.
    pub fn external_count(&self, name: &str) -> Option<u64> {
        let id = self.program.plan.graph.resource_id(name)?;
        self.buffers.external_counts.get(&id).copied()
    }

    /// The default of parameter `name`, or an error listing the parameters.
    fn parameter_default(&self, name: &str) -> Result<ConstValue> {
        self.program.plan.graph.parameters.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = self.program.plan.graph.parameters.keys().map(|s| s.as_str()).collect();
            Error::Runtime(format!(
                "graph '{}' has no parameter '{name}' (parameters: {})",
                self.program.plan.graph.name,
                known.join(", ")
            ))
        })
    }

    /// Sets parameter `name` for every later frame; the value must have the parameter's
    /// type.
    pub fn set_parameter(&mut self, name: &str, value: ConstValue) -> Result<()> {
        let default = self.parameter_default(name)?;
        if default.wgsl_type() != value.wgsl_type() {
            return Err(Error::Runtime(format!(
                "parameter '{name}' is {} but was given as {}",
                default.wgsl_type(),
                value.wgsl_type()
            )));
        }
        self.parameters.insert(name.to_string(), ParameterSource::Fixed(value));
        Ok(())
    }

    /// Sets parameter `name` to `schedule(frame index)` in every later frame (converted to
    /// the parameter's type).
    pub fn set_parameter_schedule(
        &mut self,
        name: &str,
        schedule: impl Fn(u32) -> f64 + Send + Sync + 'static,
    ) -> Result<()> {
        let default = self.parameter_default(name)?;
        self.parameters.insert(
            name.to_string(),
            ParameterSource::Schedule(Box::new(move |frame| default.with_number(schedule(frame)))),
        );
        Ok(())
    }

    /// The parameters' values in frame `index`, in frame-record order.
    fn parameters_of_frame(&self, index: u32) -> Vec<(String, ConstValue)> {
        self.program
            .resolved
            .parameters
            .iter()
            .map(|(name, default)| {
                let v = match self.parameters.get(name) {
                    Some(ParameterSource::Fixed(v)) => *v,
                    Some(ParameterSource::Schedule(f)) => f(index),
                    None => *default,
                };
                (name.clone(), v)
            })
            .collect()
    }

    /// Counter totals since the instance was created.
    pub fn counter_totals(&self) -> BTreeMap<String, u64> {
        self.program
            .plan
            .graph
            .counters
            .iter()
            .cloned()
            .zip(self.frames.totals.iter().copied())
            .collect()
    }

    /// The id and the slot of the allocated resource `name`.
    fn resource(&self, name: &str) -> Result<(ResourceId, Slot)> {
        let g = &self.program.plan.graph;
        let Some(id) = g.resource_id(name) else {
            return Err(Error::Runtime(format!("graph '{}' has no resource '{name}'", g.name)));
        };
        self.buffers
            .slots
            .get(&BufferRef::Resource(id))
            .map(|&slot| (id, slot))
            .ok_or_else(|| {
                Error::Runtime(format!(
                    "resource '{name}' of graph '{}' is not allocated: no live pass or operator uses it",
                    g.name
                ))
            })
    }

    /// Reads a resource's bytes back to the host (a transient one holds what its last use
    /// in the last frame left, unless memory it shares was written since).
    pub fn read(&self, name: &str) -> Result<Vec<u8>> {
        let (_, slot) = self.resource(name)?;
        let size = slot.size.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resource readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(self.buffers.buffer(slot), slot.offset, &staging, 0, size);
        self.gpu.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait()?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapping '{name}' failed: {e}")))?
            .to_vec();
        Ok(data[..slot.size as usize].to_vec())
    }

    /// Overwrites a resource's bytes (from the start).
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        let (_, slot) = self.resource(name)?;
        if bytes.len() as u64 > slot.size {
            return Err(Error::Runtime(format!(
                "{} bytes do not fit resource '{name}' ({} bytes)",
                bytes.len(),
                slot.size
            )));
        }
        self.gpu
            .queue
            .write_buffer(self.buffers.buffer(slot), slot.offset, bytes);
        Ok(())
    }

    /// Keeps a copy of resource `name`'s bytes on the GPU (queued after the work before it)
    /// for [`Instance::restore`]: inputs that an operator changes in place are put back
    /// between runs without a host upload. A later snapshot of the name replaces it.
    pub fn snapshot(&mut self, name: &str) -> Result<()> {
        let (id, slot) = self.resource(name)?;
        let copy = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resource snapshot"),
            size: slot.size,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(self.buffers.buffer(slot), slot.offset, &copy, 0, slot.size);
        self.gpu.queue.submit([encoder.finish()]);
        self.snapshots.insert(id, copy);
        Ok(())
    }

    /// Puts resource `name`'s last [`Instance::snapshot`] back, on the GPU (queued before the
    /// next frame).
    pub fn restore(&self, name: &str) -> Result<()> {
        let (id, slot) = self.resource(name)?;
        let copy = self
            .snapshots
            .get(&id)
            .ok_or_else(|| Error::Runtime(format!("resource '{name}' has no snapshot to restore")))?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(copy, 0, self.buffers.buffer(slot), slot.offset, slot.size);
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Sets a resource to zero.
    pub fn clear(&self, name: &str) -> Result<()> {
        let (_, slot) = self.resource(name)?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(self.buffers.buffer(slot), slot.offset, Some(slot.size));
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }
}
