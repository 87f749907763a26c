//! The GPU buffers of an instance: the arenas that transient buffers share, the buffers of
//! their own of everything else, the host's external data, and the engine's small buffers.

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::ids::ResourceId;
use crate::ir::Scope;
use crate::program::Program;
use crate::resolve::BufferRef;
use std::collections::BTreeMap;

/// A buffer's bytes: which GPU buffer, where, how many.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slot {
    /// Index into [`Buffers::gpu`].
    pub buffer: usize,
    /// Byte offset.
    pub offset: u64,
    /// Bytes.
    pub size: u64,
}

/// Every buffer of an instance.
pub struct Buffers {
    /// The GPU buffers: arenas first.
    pub gpu: Vec<wgpu::Buffer>,
    /// Where each logical buffer lives.
    pub slots: BTreeMap<BufferRef, Slot>,
    /// Element counts of the external resources, as supplied.
    pub external_counts: BTreeMap<ResourceId, u64>,
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

impl Buffers {
    /// Allocates the program's buffers and uploads `externals`.
    pub fn new(gpu: &Gpu, program: &Program, externals: &BTreeMap<String, Vec<u8>>) -> Result<Buffers> {
        let mut b = Buffers {
            gpu: Vec::new(),
            slots: BTreeMap::new(),
            external_counts: BTreeMap::new(),
        };
        let memory = &program.resolved.memory;
        for (i, &size) in memory.arenas.iter().enumerate() {
            b.make(gpu, &format!("arena {i}"), size, STORAGE, false)?;
        }
        for (r, p) in &memory.placements {
            let slot = match p.arena {
                Some(a) => Slot {
                    buffer: a,
                    offset: p.offset,
                    size: p.bytes,
                },
                None => b.make(gpu, &r.describe(&program.plan), p.bytes, STORAGE, true)?,
            };
            b.slots.insert(r.clone(), slot);
        }
        b.upload_externals(gpu, program, externals)?;
        let ncounters = program.plan.graph.counters.len() as u64;
        let nargs = (program.resolved.queue_capacity.len()
            + program.plan.boundaries.len()
            + program.resolved.control.domain.len()) as u64;
        let engine = [
            (BufferRef::Counters, "counters", 4 * ncounters, STORAGE),
            (BufferRef::Totals, "counter totals", 8 * ncounters, STORAGE),
            (
                BufferRef::Control,
                "control words",
                4 * program.resolved.control.len as u64,
                STORAGE,
            ),
            (
                BufferRef::Args,
                "indirect arguments",
                12 * nargs,
                STORAGE | wgpu::BufferUsages::INDIRECT,
            ),
        ];
        for (r, label, size, usage) in engine {
            let slot = b.make(gpu, label, size, usage, true)?;
            b.slots.insert(r, slot);
        }
        Ok(b)
    }

    /// A GPU buffer of its own (at least 16 bytes), as a slot of `size` bytes; one `bound`
    /// whole must fit a storage binding (arenas are bound in ranges).
    fn make(&mut self, gpu: &Gpu, label: &str, size: u64, usage: wgpu::BufferUsages, bound: bool) -> Result<Slot> {
        let bytes = size.max(16).next_multiple_of(4);
        let max_binding = gpu.limits.max_storage_buffer_binding_size;
        if bound && usage.contains(wgpu::BufferUsages::STORAGE) && bytes > max_binding {
            return Err(Error::Gpu(format!(
                "{label} needs {:.1} MiB but the adapter binds at most {:.1} MiB per storage buffer; use fewer items per frame (or max_items_in_flight, threads)",
                bytes as f64 / 1048576.0,
                max_binding as f64 / 1048576.0
            )));
        }
        if bytes > gpu.limits.max_buffer_size {
            return Err(Error::Gpu(format!(
                "{label} needs {:.1} MiB but the adapter's buffers hold at most {:.1} MiB",
                bytes as f64 / 1048576.0,
                gpu.limits.max_buffer_size as f64 / 1048576.0
            )));
        }
        self.gpu.push(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage,
            mapped_at_creation: false,
        }));
        Ok(Slot {
            buffer: self.gpu.len() - 1,
            offset: 0,
            size: size.max(4),
        })
    }

    /// Buffers of the external resources the live graph uses, filled with the host's data.
    /// Data for a candidate resource that no pass of the program uses is left aside.
    fn upload_externals(&mut self, gpu: &Gpu, program: &Program, externals: &BTreeMap<String, Vec<u8>>) -> Result<()> {
        let g = &program.plan.graph;
        for name in externals.keys() {
            let unused_candidate = g.resource(name).is_none() && g.declared.candidates.contains_key(name);
            if !unused_candidate && g.resource(name).is_none_or(|r| r.decl.scope != Scope::External) {
                return Err(Error::Runtime(format!(
                    "data given for '{name}', which graph '{}' has no external resource of that name",
                    g.name
                )));
            }
        }
        for id in g.resource_ids() {
            let (name, r) = (&g.resources[id].name, &g.resources[id].decl);
            if r.scope != Scope::External || !program.resolved.used.contains(&id) {
                continue;
            }
            let elem = program.resolved.sizes[id].element_bytes as u64;
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
            self.external_counts.insert(id, bytes.len() as u64 / elem);
            let slot = self.make(
                gpu,
                &format!("resource '{name}'"),
                (bytes.len() as u64).max(elem),
                STORAGE,
                true,
            )?;
            gpu.queue.write_buffer(&self.gpu[slot.buffer], 0, bytes);
            self.slots.insert(BufferRef::Resource(id), slot);
        }
        Ok(())
    }

    /// The GPU buffer of a slot.
    pub fn buffer(&self, slot: Slot) -> &wgpu::Buffer {
        &self.gpu[slot.buffer]
    }

    /// The slot of a logical buffer.
    pub fn slot(&self, r: &BufferRef) -> Slot {
        self.slots[r]
    }

    /// The binding of a logical buffer.
    pub fn binding(&self, r: &BufferRef) -> wgpu::BindingResource<'_> {
        let s = self.slots[r];
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.gpu[s.buffer],
            offset: s.offset,
            size: wgpu::BufferSize::new(s.size),
        })
    }
}
