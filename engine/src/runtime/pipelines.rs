//! Pipelines and bind groups of every kernel of a program. Group 0 holds the kernel's
//! buffers (ranges of arenas for transient ones); group 1 the frame record, shared by all.

use super::Kernels;
use super::buffers::Buffers;
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::plan::{Port, Side};
use crate::program::{BindingUse, KernelModule, Program, RuntimeChecks};
use crate::resolve::BufferRef;
use std::any::Any;
use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::panic::AssertUnwindSafe;

/// Maps a kernel's virtual boundary bindings to physical buffers.
type Resolve = Box<dyn Fn(&BufferRef) -> BufferRef>;

/// Bytes of one frame record (and of its binding).
pub const RECORD_STRIDE: u64 = 256;

/// A pipeline with its bind groups: one, or one per iteration parity for kernels that use a
/// ping-pong boundary, or one per physical buffer of a boundary.
pub struct Kernel {
    pub pipeline: wgpu::ComputePipeline,
    pub bind_groups: Vec<wgpu::BindGroup>,
    /// Whether it reads the frame record (group 1, dynamic offset).
    pub uses_frame: bool,
    /// Its slot in the timing table, for kernels whose GPU time is reported.
    pub timing: Option<usize>,
}

/// The physical boundary buffer a port uses in iteration `parity`.
pub fn physical(program: &Program, port: Port, parity: usize) -> BufferRef {
    let side = if program.plan.boundaries[port.boundary].pingpong {
        (parity + (port.side == Side::Next) as usize) % 2
    } else {
        0
    };
    BufferRef::Boundary(port.boundary, side)
}

/// The layout of the frame record's group.
pub fn frame_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame record"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(RECORD_STRIDE),
            },
            count: None,
        }],
    })
}

/// Builds pipelines and bind groups.
struct Builder<'a> {
    device: &'a wgpu::Device,
    buffers: &'a Buffers,
    frame_layout: &'a wgpu::BindGroupLayout,
    timed_names: Vec<String>,
    /// The kernel being built, named by an error if its translation panics.
    current: &'a RefCell<String>,
}

impl Builder<'_> {
    /// A kernel with one bind group per entry of `resolves`, which map the virtual boundary
    /// bindings to physical buffers; `timed` kernels get a timing slot.
    fn kernel(&mut self, module: &KernelModule, resolves: &[&dyn Fn(&BufferRef) -> BufferRef], timed: bool) -> Kernel {
        let name = &module.name;
        self.current.replace(name.clone());
        let group0: Vec<&BindingUse> = module.uses.iter().filter(|u| !u.uniform).collect();
        let uses_frame = module.uses.iter().any(|u| u.uniform);
        let entries: Vec<wgpu::BindGroupLayoutEntry> = group0
            .iter()
            .map(|u| wgpu::BindGroupLayoutEntry {
                binding: u.binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: u.read_only },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let bgl = self.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(name),
            entries: &entries,
        });
        let mut layouts = vec![Some(&bgl)];
        if uses_frame {
            layouts.push(Some(self.frame_layout));
        }
        let layout = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &layouts,
            immediate_size: 0,
        });
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(name),
            source: wgpu::ShaderSource::Naga(Cow::Owned(module.module.clone())),
        };
        let shader = match module.checks {
            RuntimeChecks::All => self.device.create_shader_module(desc),
            // SAFETY: bounds checks stay; the layout declares that its kernels' loops all end
            // (LayoutDecl::loop_guards).
            RuntimeChecks::NoLoopGuards => unsafe {
                let checks = wgpu::ShaderRuntimeChecks {
                    force_loop_bounding: false,
                    ..wgpu::ShaderRuntimeChecks::checked()
                };
                self.device.create_shader_module_trusted(desc, checks)
            },
            // SAFETY: the engine's own kernels index only below lengths they check (their
            // element counts are validated against the buffers when the program is resolved)
            // and loop a bounded number of times.
            RuntimeChecks::None => unsafe {
                self.device
                    .create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
            },
        };
        let pipeline = self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
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
                let entries: Vec<wgpu::BindGroupEntry> = group0
                    .iter()
                    .map(|u| wgpu::BindGroupEntry {
                        binding: u.binding,
                        resource: self.buffers.binding(&resolve(&u.buffer)),
                    })
                    .collect();
                self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(name),
                    layout: &bgl,
                    entries: &entries,
                })
            })
            .collect();
        let timing = timed.then(|| {
            self.timed_names.push(name.clone());
            self.timed_names.len() - 1
        });
        Kernel {
            pipeline,
            bind_groups,
            uses_frame,
            timing,
        }
    }
}

/// Every kernel of `program` as a pipeline bound to `buffers`. naga validated every module,
/// but its translation to the driver's language can still panic on a construct it mishandles:
/// that is an error naming the kernel, not a crash.
pub fn build(gpu: &Gpu, program: &Program, buffers: &Buffers) -> Result<Kernels> {
    let current = RefCell::new(String::new());
    std::panic::catch_unwind(AssertUnwindSafe(|| build_kernels(gpu, program, buffers, &current))).unwrap_or_else(
        |panic| {
            Err(translation_error(
                &program.plan.layout_name,
                &current.borrow(),
                panic.as_ref(),
            ))
        },
    )
}

/// The error of a kernel whose translation panicked with `panic`.
fn translation_error(layout: &str, kernel: &str, panic: &(dyn Any + Send)) -> Error {
    let message = panic
        .downcast_ref::<&str>()
        .map(|m| m.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into());
    Error::Shader(format!(
        "layout '{layout}', kernel '{kernel}': naga panicked translating it for the driver ({message}). \
         That is a bug of naga's, not an error in the WGSL, which validated; one known trigger is \
         passing a pointer to a field reached through a pointer parameter on to another function \
         (`f(&(*p).field)`): pass a local copy of the field and store it back"
    ))
}

/// [`build`]'s work, naming the kernel it builds in `current`.
fn build_kernels(gpu: &Gpu, program: &Program, buffers: &Buffers, current: &RefCell<String>) -> Result<Kernels> {
    let device = &gpu.device;
    let frame_layout = frame_layout(device);
    let mut b = Builder {
        device,
        buffers,
        frame_layout: &frame_layout,
        timed_names: Vec::new(),
        current,
    };
    let identity = |r: &BufferRef| r.clone();
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let mut passes = Vec::new();
    for (km, kp) in program.kernels.iter().zip(&program.plan.kernels) {
        let resolve = |parity: usize| {
            let (input, output) = (kp.input, kp.output);
            move |r: &BufferRef| match r {
                BufferRef::BoundaryIn => physical(program, input.expect("reads a boundary"), parity),
                BufferRef::BoundaryOut => physical(program, output.expect("writes a boundary"), parity),
                other => other.clone(),
            }
        };
        let (even, odd) = (resolve(0), resolve(1));
        passes.push(b.kernel(km, &[&even, &odd], true));
    }
    let nqueues = program.resolved.queue_capacity.len();
    let args = program
        .plan
        .queued_streams
        .iter()
        .enumerate()
        .map(|(i, &q)| (q, (b.kernel(&program.args[&q], &[&identity], false), 12 * i as u64)))
        .collect();
    let mut commits = Vec::new();
    for (i, boundary) in program.plan.boundaries.iter().enumerate() {
        let sides: Vec<Resolve> = (0..1 + boundary.pingpong as usize)
            .map(|side| {
                Box::new(move |r: &BufferRef| {
                    if *r == BufferRef::BoundaryIn {
                        BufferRef::Boundary(crate::ids::BoundaryId(i), side)
                    } else {
                        r.clone()
                    }
                }) as Resolve
            })
            .collect();
        let refs: Vec<&dyn Fn(&BufferRef) -> BufferRef> = sides.iter().map(|f| f.as_ref()).collect();
        let [reset, add] = &program.commits[i];
        commits.push((
            [b.kernel(reset, &refs, false), b.kernel(add, &refs, false)],
            12 * (nqueues + i) as u64,
        ));
    }
    let zeros = program
        .zeros
        .iter()
        .map(|(&w, m)| (w, b.kernel(m, &[&identity], false)))
        .collect();
    let first_domain = nqueues + program.plan.boundaries.len();
    let domains = program
        .domains
        .iter()
        .enumerate()
        .map(|(i, (&ph, m))| (ph, (b.kernel(m, &[&identity], false), 12 * (first_domain + i) as u64)))
        .collect();
    let ops = program
        .ops
        .iter()
        .map(|op| {
            op.kernels
                .iter()
                .map(|(m, groups)| (b.kernel(m, &[&identity], true), *groups))
                .collect()
        })
        .collect();
    let fold = b.kernel(&program.fold, &[&identity], false);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!(
            "creating the pipelines of layout '{}' failed: {e}",
            program.plan.layout_name
        )));
    }
    Ok(Kernels {
        passes,
        args,
        commits,
        zeros,
        domains,
        ops,
        fold,
        timed_names: b.timed_names,
        frame_layout,
    })
}

/// Kernel names by timing slot, merged into per-name seconds.
pub fn kernel_seconds(names: &[String], slots: &[usize], ticks: &[u64], period: f64) -> BTreeMap<String, f64> {
    let mut out = BTreeMap::new();
    for (i, &slot) in slots.iter().enumerate() {
        let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period;
        *out.entry(names[slot].clone()).or_insert(0.0) += dt;
    }
    out
}
