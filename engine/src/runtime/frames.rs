//! Running batches of frames: the frame records (chunk and parameters), the frame's steps
//! (phases chunk by chunk, operators), host-driven loops, and the read-back of control
//! words, counters and timestamps, which a caller may collect while the next batch runs
//! (two batches in flight, each with its own records and read-back buffers).

use super::Instance;
use super::pipelines::{Kernel, RECORD_STRIDE, kernel_seconds, physical};
use super::recorder::{MAX_QUERIES, MAX_TIMED, Recorder};
use super::{FrameStats, IN_FLIGHT, MAX_BATCH};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::FrameStep;
use crate::ids::{ChainId, KernelId, OpId, PhaseId};
use crate::operator::OpKind;
use crate::plan::{Port, Root, Step};
use crate::program::Program;
use crate::resolve::{BOUNDARY_HEADER, BufferRef};
use std::collections::{BTreeMap, VecDeque};

/// Host loop iterations after which a loop is declared stuck.
const MAX_HOST_ITERATIONS: u32 = 1 << 20;
/// Dispatches after which a batch being recorded is submitted, so that the GPU runs its
/// first frames while the host records the rest.
const SUBMIT_EVERY: u32 = 512;

/// The per-instance state of running frames.
pub struct FrameState {
    /// The buffers of each batch that can be in flight.
    slots: [BatchSlot; IN_FLIGHT],
    /// The slot of the batch being recorded.
    current: usize,
    /// The records of the batch being recorded: index, seed, base, count, parameters.
    records: Vec<Vec<u32>>,
    /// Where host loops read back whether work is left.
    loop_readback: wgpu::Buffer,
    /// Where a batch's read-back holds what.
    readback: Readback,
    /// Counter totals since the instance was created, as of the last batch collected.
    pub totals: Vec<u64>,
    /// Host loop iterations the previous frame needed, per loop (the next frame's first batch).
    last_iterations: BTreeMap<usize, u32>,
    /// The bounded loops of the batch being recorded, each with its copy in the slot's
    /// check buffer.
    checks: Vec<LoopCheck>,
    /// Batches submitted and not yet collected, oldest first.
    in_flight: VecDeque<Pending>,
}

/// The buffers one batch in flight uses: its frame records, timestamp queries and read-backs.
struct BatchSlot {
    /// Frame records, one per chunk of a phase and per operator of each frame of a batch.
    records_buffer: wgpu::Buffer,
    /// The frame record's bind group (group 1).
    frame_group: wgpu::BindGroup,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    /// Control words, counter totals and timestamps at the batch's end.
    readback: wgpu::Buffer,
    /// Copies of the control words (and boundary headers) after each bounded loop of the
    /// batch.
    check_buffer: wgpu::Buffer,
}

/// A submitted batch whose read-back waits to be collected.
struct Pending {
    slot: usize,
    /// The batch's last submission: its read-back is ready once this one has run.
    submission: wgpu::SubmissionIndex,
    checks: Vec<LoopCheck>,
    /// Timing slot of each timestamp pair the batch wrote.
    timed: Vec<usize>,
    host_iterations: u32,
}

/// Checks a bounded loop can record per batch before it falls back to a host read-back.
const MAX_CHECKS: u64 = 256;

/// A bounded host loop whose end the batch's read-back checks.
#[derive(Debug, Clone)]
struct LoopCheck {
    chain: ChainId,
    /// Iterations it ran.
    bound: u32,
    /// Items of the chunk the loop ran for.
    items: u64,
    /// Byte offset of its copy of the control words in the check buffer.
    at: u64,
    /// Byte offsets of its copies of the chain's boundary headers.
    headers: Vec<u64>,
}

/// What one record of a batch runs.
#[derive(Debug, Clone, Copy)]
enum Run {
    /// A chunk of a phase; `first` for the phase's first chunk of the frame.
    Chunk { phase: PhaseId, step: usize, first: bool },
    /// An operator over `n` elements.
    Op { op: OpId, step: usize, n: u64 },
}

/// How many workgroups a dispatch runs.
#[derive(Clone, Copy)]
enum Dispatch {
    /// Enough workgroups of the layout's size for this many items.
    Items(u64),
    /// This many workgroups.
    Groups(u64),
    /// From the indirect arguments at this byte offset.
    Indirect(u64),
    /// One workgroup.
    Single,
}

impl FrameState {
    pub fn new(gpu: &Gpu, program: &Program, layout: &wgpu::BindGroupLayout) -> FrameState {
        let device = &gpu.device;
        let readback = Readback::of(program);
        let slots = std::array::from_fn(|_| BatchSlot::new(gpu, program, layout, &readback));
        let loop_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("loop readback"),
            size: check_bytes(program),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        FrameState {
            slots,
            current: 0,
            records: Vec::new(),
            loop_readback,
            readback,
            totals: vec![0; program.plan.graph.counters.len()],
            last_iterations: BTreeMap::new(),
            checks: Vec::new(),
            in_flight: VecDeque::new(),
        }
    }

    /// The timestamp queries of the batch being recorded.
    fn queries(&self) -> &Option<(wgpu::QuerySet, wgpu::Buffer)> {
        &self.slots[self.current].queries
    }
}

impl BatchSlot {
    fn new(gpu: &Gpu, program: &Program, layout: &wgpu::BindGroupLayout, readback: &Readback) -> BatchSlot {
        let device = &gpu.device;
        let records_buffer = records_buffer(device, 64);
        let frame_group = frame_group(device, layout, &records_buffer);
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
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: readback.bytes(MAX_TIMED as u64),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let check_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("loop checks"),
            size: MAX_CHECKS * check_bytes(program),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        BatchSlot {
            records_buffer,
            frame_group,
            queries,
            readback,
            check_buffer,
        }
    }
}

/// Where a batch's read-back holds what: the control words first, then the counter totals
/// (8 bytes each), then the timestamp pairs (16 bytes each).
struct Readback {
    control_bytes: u64,
    totals_at: u64,
    ts_at: u64,
}

impl Readback {
    fn of(program: &Program) -> Readback {
        let control_bytes = (4 * program.resolved.control.len as u64).max(16);
        let totals_at = control_bytes.next_multiple_of(8);
        let ts_at = totals_at + 8 * program.plan.graph.counters.len() as u64;
        Readback {
            control_bytes,
            totals_at,
            ts_at,
        }
    }

    /// Bytes used with `pairs` timestamp pairs.
    fn bytes(&self, pairs: u64) -> u64 {
        (self.ts_at + 16 * pairs).next_multiple_of(8)
    }
}

/// The most bytes one loop check takes: the control words and every boundary header.
fn check_bytes(program: &Program) -> u64 {
    let sides: u64 = program.plan.boundaries.iter().map(|b| 1 + b.pingpong as u64).sum();
    // The control words' slot is at least 16 bytes (see `Buffers`).
    (4 * program.resolved.control.len as u64).max(16).next_multiple_of(8) + 8 * sides
}

fn records_buffer(device: &wgpu::Device, records: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("frame records"),
        size: records as u64 * RECORD_STRIDE,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn frame_group(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, records: &wgpu::Buffer) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("frame record"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: records,
                offset: 0,
                size: wgpu::BufferSize::new(RECORD_STRIDE),
            }),
        }],
    })
}

impl Instance<'_> {
    /// Runs frame `index` with `seed`: every step of the frame.
    pub fn run_frame(&mut self, index: u32, seed: u32) -> Result<FrameStats> {
        self.run_frames(index, 1, seed)
    }

    /// Runs frames `first .. first + count` (at most [`MAX_BATCH`]) with `seed`, recorded
    /// together and read back once, and waits for them: the statistics are the batch's,
    /// with those of any batch submitted before and not yet collected.
    pub fn run_frames(&mut self, first: u32, count: u32, seed: u32) -> Result<FrameStats> {
        self.submit_frames(first, count, seed)?;
        let mut stats = FrameStats::default();
        while let Some(s) = self.collect_frames()? {
            stats.add(&s);
        }
        Ok(stats)
    }

    /// Batches submitted and not yet collected.
    pub fn frames_in_flight(&self) -> usize {
        self.frames.in_flight.len()
    }

    /// Records frames `first .. first + count` (at most [`MAX_BATCH`]) with `seed` and submits
    /// them without waiting; [`Instance::collect_frames`] reads their statistics back later,
    /// so the host can record the next batch while the GPU runs this one. At most
    /// [`IN_FLIGHT`] batches can be in flight. Host loops without a loop bound still wait for
    /// the GPU within the batch.
    pub fn submit_frames(&mut self, first: u32, count: u32, seed: u32) -> Result<()> {
        if count == 0 || count > MAX_BATCH {
            return Err(Error::Runtime(format!(
                "a batch runs 1 to {MAX_BATCH} frames, not {count}"
            )));
        }
        if self.frames.in_flight.len() >= IN_FLIGHT {
            return Err(Error::Runtime(format!(
                "{IN_FLIGHT} batches are in flight already: collect one first"
            )));
        }
        self.frames.current = self.frames.in_flight.back().map_or(0, |p| (p.slot + 1) % IN_FLIGHT);
        self.frames.checks.clear();
        let runs = self.write_records(first, count, seed)?;
        let scope = self.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut rec = Recorder::new(&self.gpu.device);
        let control = self.buffers.slot(&BufferRef::Control);
        rec.clear(self.buffers.buffer(control), control.offset, control.size);
        for (slot, bytes) in self.item_clears(None) {
            rec.clear(self.buffers.buffer(slot), slot.offset, bytes);
        }
        for (record, run) in runs.into_iter().enumerate() {
            match run {
                Run::Chunk { phase, step, first } => {
                    if first {
                        self.clear_transients(&mut rec, step);
                    }
                    self.run_chunk(&mut rec, phase, record)?;
                }
                Run::Op { op, step, n } => {
                    self.clear_transients(&mut rec, step);
                    self.run_operator(&mut rec, op, n, record);
                }
            }
            if rec.unsubmitted >= SUBMIT_EVERY {
                rec.submit(&self.gpu.device, &self.gpu.queue);
            }
        }
        let slot = self.frames.current;
        rec.resolve(&self.frames.slots[slot].queries);
        self.copy_read_back(&mut rec);
        let submission = self.gpu.queue.submit([rec.encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!("running a frame failed: {e}")));
        }
        self.frames.in_flight.push_back(Pending {
            slot,
            submission,
            checks: std::mem::take(&mut self.frames.checks),
            timed: rec.timed,
            host_iterations: rec.host_iterations,
        });
        Ok(())
    }

    /// The records of the batch (written to the GPU) and what each runs.
    fn write_records(&mut self, first: u32, count: u32, seed: u32) -> Result<Vec<Run>> {
        let g = &self.program.plan.graph;
        let resolved = &self.program.resolved;
        let mut records: Vec<Vec<u32>> = Vec::new();
        let mut runs = Vec::new();
        for index in first..first + count {
            let parameters = self.parameters_of_frame(index);
            let mut vars: BTreeMap<String, f64> = resolved
                .constants
                .iter()
                .map(|(k, v)| (k.clone(), v.as_f64()))
                .collect();
            vars.extend(parameters.iter().map(|(k, v)| (k.clone(), v.as_f64())));
            let words = |base: u64, n: u64| {
                let mut r = vec![index, seed, base as u32, n as u32];
                r.extend(parameters.iter().map(|(_, v)| v.bits()));
                r
            };
            for (step, s) in g.steps.iter().enumerate() {
                match *s {
                    FrameStep::Phase(ph) => {
                        let d = &resolved.domains[ph.0];
                        let total = d
                            .over
                            .count(&vars)
                            .map_err(|e| Error::Runtime(format!("frame {index}: the items of phase {ph}: {e}")))?;
                        let mut base = 0u64;
                        loop {
                            let n = d.chunk.min(total - base);
                            runs.push(Run::Chunk {
                                phase: ph,
                                step,
                                first: base == 0,
                            });
                            records.push(words(base, n));
                            base += n;
                            if base >= total {
                                break;
                            }
                        }
                    }
                    FrameStep::Op(o) => {
                        let (base, n, words_n) = self.operator_range(o, &vars)?;
                        runs.push(Run::Op { op: o, step, n });
                        records.push(words(base, words_n));
                    }
                }
            }
        }
        let slot = &mut self.frames.slots[self.frames.current];
        if records.len() * RECORD_STRIDE as usize > slot.records_buffer.size() as usize {
            let device = &self.gpu.device;
            slot.records_buffer = records_buffer(device, records.len().next_power_of_two());
            slot.frame_group = frame_group(device, &self.kernels.frame_layout, &slot.records_buffer);
        }
        let mut bytes = vec![0u8; records.len() * RECORD_STRIDE as usize];
        for (i, r) in records.iter().enumerate() {
            bytes[i * RECORD_STRIDE as usize..][..4 * r.len()].copy_from_slice(bytemuck::cast_slice(r));
        }
        self.gpu.queue.write_buffer(&slot.records_buffer, 0, &bytes);
        self.frames.records = records;
        Ok(runs)
    }

    /// An operator's record this frame: base, elements, and the count its record holds
    /// (a fill's record holds its first word and words).
    fn operator_range(&self, o: OpId, vars: &BTreeMap<String, f64>) -> Result<(u64, u64, u64)> {
        let op = &self.program.plan.graph.ops[o];
        let resolved = &self.program.resolved;
        let sized = resolved.op_elements[&o];
        let fail = |e: String| Error::Runtime(format!("operator '{}': {e}", op.name));
        // A counted operator runs over at most this frame's `over`.
        let n = match &op.domain {
            Some(d) => d.over.count(vars).map_err(fail)?,
            None => sized,
        };
        if n > sized {
            return Err(fail(format!(
                "{n} elements this frame, but its buffers were sized for {sized}"
            )));
        }
        Ok(match &op.kind {
            OpKind::Clear { buffer, first, .. } => {
                let w = resolved.sizes[*buffer].element_bytes as u64 / 4;
                let first = first.as_ref().map_or(Ok(0), |e| e.count(vars)).map_err(fail)?;
                (first * w, n, n * w)
            }
            _ => (0, n, n),
        })
    }

    /// Zeroes the transient resources declared `clear: true` whose lifetime starts at `step`.
    fn clear_transients(&self, rec: &mut Recorder, step: usize) {
        for &r in self.program.resolved.clears.get(&step).into_iter().flatten() {
            let slot = self.buffers.slot(&BufferRef::Resource(r));
            rec.clear(self.buffers.buffer(slot), slot.offset, slot.size);
        }
    }

    /// One chunk of a phase: its alive flags and boundary headers cleared (their memory may
    /// be shared), regeneration counters zeroed, a counted domain counted, the schedule run,
    /// the counters folded.
    fn run_chunk(&mut self, rec: &mut Recorder, ph: PhaseId, record: usize) -> Result<()> {
        for (slot, bytes) in self.item_clears(Some(ph)) {
            rec.clear(self.buffers.buffer(slot), slot.offset, bytes);
        }
        let plan = &self.program.plan;
        for k in plan.kernels.iter().filter(|k| k.phase == ph && k.regenerates) {
            let word = self.program.resolved.control.next[&k.chain];
            self.dispatch(rec, &self.kernels.zeros[&word], record, Dispatch::Single);
        }
        if let Some((kernel, _)) = self.kernels.domains.get(&ph) {
            self.dispatch(rec, kernel, record, Dispatch::Single);
        }
        let steps = plan.schedule[ph.0].clone();
        self.run_steps(rec, &steps, record)?;
        self.dispatch(rec, &self.kernels.fold, record, Dispatch::Single);
        Ok(())
    }

    /// The alive flags and boundary headers that must read zero when a phase starts, with
    /// the bytes to clear: those of phase `Some(ph)` in shared memory (another buffer may have
    /// used it since), or with `None` those in memory of their own (which the last frame left
    /// at zero, so once per batch is enough).
    fn item_clears(&self, ph: Option<PhaseId>) -> Vec<(super::buffers::Slot, u64)> {
        let plan = &self.program.plan;
        let g = &plan.graph;
        let memory = &self.program.resolved.memory;
        let wanted = |r: &BufferRef, chain: ChainId| {
            let shared = memory.placements[r].arena.is_some();
            match ph {
                Some(ph) => shared && g.phase_of_chain(chain) == ph,
                None => !shared,
            }
        };
        let mut out = Vec::new();
        for &c in &plan.stored_chains {
            let r = BufferRef::Alive(c);
            // Flags of their own are left at zero by the loops that end every chunk.
            if ph.is_some() && wanted(&r, c) {
                let slot = self.buffers.slot(&r);
                out.push((slot, slot.size));
            }
        }
        for (b, boundary) in plan.boundaries.iter().enumerate() {
            for side in 0..1 + boundary.pingpong as usize {
                let r = BufferRef::Boundary(crate::ids::BoundaryId(b), side);
                if wanted(&r, boundary.chain) {
                    out.push((self.buffers.slot(&r), BOUNDARY_HEADER));
                }
            }
        }
        out
    }

    /// An operator's kernels over `n` elements (the most there can be, when counted).
    fn run_operator(&self, rec: &mut Recorder, o: OpId, n: u64, record: usize) {
        for (kernel, groups) in &self.kernels.ops[o.0] {
            self.dispatch(rec, kernel, record, Dispatch::Groups(groups.count(n)));
        }
    }

    fn dispatch(&self, rec: &mut Recorder, k: &Kernel, record: usize, groups: Dispatch) {
        let query = k.timing.and_then(|slot| rec.next_query(self.frames.queries(), slot));
        let offset = [(record as u64 * RECORD_STRIDE) as u32];
        let bind_group = &k.bind_groups[rec.parity % k.bind_groups.len()];
        let set = self.frames.queries().as_ref().map(|(set, _)| set);
        let max = self.program.target.max_workgroups_per_dimension as u64;
        let args = self.buffers.buffer(self.buffers.slot(&BufferRef::Args));
        let frame_group = &self.frames.slots[self.frames.current].frame_group;
        rec.unsubmitted += 1;
        let pass = rec.pass();
        if let (Some(i), Some(set)) = (query, set) {
            pass.write_timestamp(set, i);
        }
        pass.set_pipeline(&k.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        if k.uses_frame {
            pass.set_bind_group(1, frame_group, &offset[..]);
        }
        let workgroups = match groups {
            Dispatch::Items(n) => Some(n.div_ceil(self.program.plan.layout.workgroup_size as u64)),
            Dispatch::Groups(g) => Some(g),
            Dispatch::Single => Some(1),
            Dispatch::Indirect(offset) => {
                pass.dispatch_workgroups_indirect(args, offset);
                None
            }
        };
        if let Some(g) = workgroups.filter(|&g| g > 0) {
            let x = g.min(max);
            pass.dispatch_workgroups(x as u32, g.div_ceil(x) as u32, 1);
        }
        if let (Some(i), Some(set)) = (query, set) {
            pass.write_timestamp(set, i + 1);
        }
    }

    /// Commits a boundary buffer (its appended items become, or with `add` join, its count)
    /// and prepares the indirect arguments for its consumer; returns their offset.
    fn commit(&self, rec: &mut Recorder, port: Port, record: usize, add: bool) -> u64 {
        let (kernels, offset) = &self.kernels.commits[port.boundary.0];
        let side = match physical(&self.program, port, rec.parity) {
            BufferRef::Boundary(_, side) => side,
            _ => unreachable!("boundary ports map to boundary buffers"),
        };
        let saved = rec.parity;
        rec.parity = side;
        self.dispatch(rec, &kernels[add as usize], record, Dispatch::Single);
        rec.parity = saved;
        *offset
    }

    fn run_kernel(&self, rec: &mut Recorder, k: KernelId, record: usize) {
        let plan = &self.program.plan;
        let kp = &plan.kernels[k];
        let items = match (self.program.resolved.pools.get(&kp.chain), &kp.root) {
            (Some(&pool), _) => Dispatch::Items(pool),
            (None, Root::Start) => match self.kernels.domains.get(&kp.phase) {
                Some((_, offset)) => Dispatch::Indirect(*offset),
                None => Dispatch::Items(self.record_items(record)),
            },
            (None, _) => Dispatch::Items(self.record_items(record)),
        };
        let kernel = &self.kernels.passes[k.0];
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
                    items
                };
                self.dispatch(rec, kernel, record, groups);
            }
            (None, Some(output)) => {
                self.commit(rec, output, record, false);
                self.dispatch(rec, kernel, record, items);
            }
            (None, None) => self.dispatch(rec, kernel, record, items),
        }
    }

    fn run_steps(&mut self, rec: &mut Recorder, steps: &[Step], record: usize) -> Result<()> {
        for (i, step) in steps.iter().enumerate() {
            match step {
                Step::Run(k) => self.run_kernel(rec, *k, record),
                Step::Drain(q) => {
                    let (args, offset) = &self.kernels.args[q];
                    self.dispatch(rec, args, record, Dispatch::Single);
                    let k = self.program.plan.consumer_kernel(*q);
                    self.dispatch(rec, &self.kernels.passes[k.0], record, Dispatch::Indirect(*offset));
                }
                Step::Loop { chain, body } => self.run_loop(rec, *chain, body, record, i)?,
            }
        }
        Ok(())
    }

    /// A host-driven loop: with a loop bound and every item starting in the first
    /// iteration, the bound's iterations with no read-back (checked with the batch);
    /// otherwise the body in growing batches of iterations, until no item of the chain is
    /// alive.
    fn run_loop(&mut self, rec: &mut Recorder, chain: ChainId, body: &[Step], record: usize, i: usize) -> Result<()> {
        rec.parity = 0;
        if let Some(bound) = self.bounded_iterations(chain, record) {
            for _ in 0..bound {
                self.run_iteration(rec, chain, body, record)?;
            }
            rec.host_iterations += bound;
            self.check_loop(rec, chain, record, bound);
            return Ok(());
        }
        // The same loop of every frame of a batch learns from the last one.
        let records = &self.frames.records;
        let per_frame = records.iter().filter(|r| r[0] == records[0][0]).count();
        let key = (record % per_frame.max(1)) * 64 + i;
        let mut batch = self.frames.last_iterations.get(&key).copied().unwrap_or(2).max(1);
        let mut done = 0u32;
        loop {
            for _ in 0..batch {
                self.run_iteration(rec, chain, body, record)?;
            }
            done += batch;
            rec.host_iterations += batch;
            if !self.loop_goes_on(rec, chain, record)? {
                break;
            }
            if done >= MAX_HOST_ITERATIONS {
                let item = &self.program.plan.graph.chains[chain].item;
                return Err(Error::Runtime(format!(
                    "items of '{item}' still alive after {done} loop iterations: a loop pass never finishes its item"
                )));
            }
            batch = (batch * 2).min(64);
        }
        self.frames.last_iterations.insert(key, done);
        Ok(())
    }

    /// One iteration of a host-driven loop: the alive count reset, the body.
    fn run_iteration(&mut self, rec: &mut Recorder, chain: ChainId, body: &[Step], record: usize) -> Result<()> {
        if let Some(word) = self.program.resolved.control.alive.get(&chain) {
            self.dispatch(rec, &self.kernels.zeros[word], record, Dispatch::Single);
        }
        self.run_steps(rec, body, record)?;
        rec.parity ^= 1;
        Ok(())
    }

    /// The iterations the loop over `chain` runs with no read-back: its graph's bound,
    /// where every item of the chunk starts in the first iteration (no pool, or a pool that
    /// holds the whole chunk) and the batch has room for one more check.
    fn bounded_iterations(&self, chain: ChainId, record: usize) -> Option<u32> {
        let bound = *self.program.resolved.loop_bounds.get(&chain)?;
        let items = self.record_items(record);
        let at_once = self
            .program
            .resolved
            .pools
            .get(&chain)
            .is_none_or(|&pool| pool >= items);
        (at_once && (self.frames.checks.len() as u64) < MAX_CHECKS).then_some(bound)
    }

    /// Copies what tells whether the bounded loop over `chain` left work (the control words
    /// and its boundaries' headers) for the batch's read-back.
    fn check_loop(&mut self, rec: &mut Recorder, chain: ChainId, record: usize, bound: u32) {
        let at = self.frames.checks.len() as u64 * check_bytes(&self.program);
        let buffer = &self.frames.slots[self.frames.current].check_buffer;
        rec.end_pass();
        let headers = self.copy_loop_words(rec, chain, buffer, at);
        self.frames.checks.push(LoopCheck {
            chain,
            items: self.record_items(record),
            bound,
            at,
            headers,
        });
    }

    /// Records copies of the control words to `buffer` at `at` and of `chain`'s boundary
    /// headers behind them; returns the headers' offsets.
    fn copy_loop_words(&self, rec: &mut Recorder, chain: ChainId, buffer: &wgpu::Buffer, at: u64) -> Vec<u64> {
        let control = self.buffers.slot(&BufferRef::Control);
        rec.encoder
            .copy_buffer_to_buffer(self.buffers.buffer(control), control.offset, buffer, at, control.size);
        let mut next = at + control.size.next_multiple_of(8);
        let mut headers = Vec::new();
        for (b, boundary) in self.program.plan.boundaries.iter().enumerate() {
            if boundary.chain != chain {
                continue;
            }
            for side in 0..1 + boundary.pingpong as usize {
                let slot = self.buffers.slot(&BufferRef::Boundary(crate::ids::BoundaryId(b), side));
                rec.encoder
                    .copy_buffer_to_buffer(self.buffers.buffer(slot), slot.offset, buffer, next, 8);
                headers.push(next);
                next += 8;
            }
        }
        headers
    }

    /// Submits what is recorded and reads back whether the loop over `chain` has work left.
    fn loop_goes_on(&self, rec: &mut Recorder, chain: ChainId, record: usize) -> Result<bool> {
        rec.end_pass();
        let headers = self.copy_loop_words(rec, chain, &self.frames.loop_readback, 0);
        let end = headers
            .last()
            .map_or(self.buffers.slot(&BufferRef::Control).size, |h| h + 8);
        let submission = rec.submit(&self.gpu.device, &self.gpu.queue);
        let bytes = map_buffer(self.gpu, &self.frames.loop_readback, end, submission)?;
        Ok(self.work_left(&bytes, 0, &headers, chain, self.record_items(record)))
    }

    /// Items of the chunk record `record` of the batch being recorded runs over.
    fn record_items(&self, record: usize) -> u64 {
        self.frames.records[record][3] as u64
    }

    /// Whether a loop over `chain` has work left, from the copy at byte `at` of `bytes`
    /// of the control words and its boundary headers (at `headers`): items alive in slots,
    /// items appended to its boundaries, or indices not yet taken (of the chunk's `items`).
    fn work_left(&self, bytes: &[u8], at: u64, headers: &[u64], chain: ChainId, items: u64) -> bool {
        let words: &[u32] = bytemuck::cast_slice(bytes);
        let word = |w: u32| words[at as usize / 4 + w as usize];
        let control = &self.program.resolved.control;
        let alive = control.alive.get(&chain).map_or(0, |&w| word(w));
        // Counts of consumed boundaries are stale; waiting items are the appended ones.
        let pending: u64 = headers.iter().map(|&h| words[h as usize / 4 + 1] as u64).sum();
        let phase = self.program.plan.graph.phase_of_chain(chain);
        let items = match control.domain.get(&phase) {
            Some(&w) => word(w) as u64,
            None => items,
        };
        let untaken = control.next.get(&chain).is_some_and(|&w| (word(w) as u64) < items);
        alive > 0 || pending > 0 || untaken
    }

    /// An error for the first bounded loop of the batch `p` that left work.
    fn check_bounded_loops(&self, p: &Pending) -> Result<()> {
        if p.checks.is_empty() {
            return Ok(());
        }
        let end = p.checks.len() as u64 * check_bytes(&self.program);
        let buffer = &self.frames.slots[p.slot].check_buffer;
        let bytes = map_buffer(self.gpu, buffer, end, p.submission.clone())?;
        for c in &p.checks {
            if self.work_left(&bytes, c.at, &c.headers, c.chain, c.items) {
                let item = &self.program.plan.graph.chains[c.chain].item;
                return Err(Error::Runtime(format!(
                    "items of '{item}' still alive after {} loop iterations, the graph's loop_bounds for '{item}': a loop pass runs longer than its bound",
                    c.bound
                )));
            }
        }
        Ok(())
    }

    /// Records the copies of the control words, counter totals and timestamps into the
    /// batch's read-back buffer.
    fn copy_read_back(&self, rec: &mut Recorder) {
        let layout = &self.frames.readback;
        let slot = &self.frames.slots[self.frames.current];
        let control = self.buffers.slot(&BufferRef::Control);
        rec.end_pass();
        rec.encoder.copy_buffer_to_buffer(
            self.buffers.buffer(control),
            control.offset,
            &slot.readback,
            0,
            layout.control_bytes,
        );
        let ncounters = self.frames.totals.len() as u64;
        if ncounters > 0 {
            let totals = self.buffers.slot(&BufferRef::Totals);
            rec.encoder.copy_buffer_to_buffer(
                self.buffers.buffer(totals),
                totals.offset,
                &slot.readback,
                layout.totals_at,
                8 * ncounters,
            );
        }
        let pairs = rec.timed.len() as u64;
        if let (Some((_, resolve)), true) = (&slot.queries, pairs > 0) {
            rec.encoder
                .copy_buffer_to_buffer(resolve, 0, &slot.readback, layout.ts_at, 16 * pairs);
        }
    }

    /// Waits for the oldest batch in flight and reads its control words, counter totals and
    /// timestamps back: its statistics, or `None` when no batch is in flight. An overflowed
    /// queue, a bounded loop that left work or a key out of range in that batch is the error.
    pub fn collect_frames(&mut self) -> Result<Option<FrameStats>> {
        let Some(p) = self.frames.in_flight.pop_front() else {
            return Ok(None);
        };
        let layout = &self.frames.readback;
        let pairs = p.timed.len() as u64;
        let readback = &self.frames.slots[p.slot].readback;
        let data = map_buffer(self.gpu, readback, layout.bytes(pairs), p.submission.clone())?;
        let words: &[u32] = bytemuck::cast_slice(&data[..layout.control_bytes as usize]);
        self.check_overflows(words)?;
        self.check_bounded_loops(&p)?;
        self.check_loops_ended(words)?;
        let mut stats = FrameStats {
            host_iterations: p.host_iterations,
            loops_capped: words[self.program.resolved.control.loop_capped as usize],
            ..Default::default()
        };
        let g = &self.program.plan.graph;
        for (i, name) in g.counters.iter().enumerate() {
            let at = (layout.totals_at + 8 * i as u64) as usize;
            let total = u64::from_le_bytes(data[at..at + 8].try_into().expect("8 bytes"));
            stats.counters.insert(name.clone(), total - self.frames.totals[i]);
            self.frames.totals[i] = total;
        }
        if pairs > 0 {
            let period = self.gpu.queue.get_timestamp_period() as f64 * 1e-9;
            let ts = layout.ts_at as usize;
            let ticks: &[u64] = bytemuck::cast_slice(&data[ts..ts + 16 * pairs as usize]);
            stats.kernel_seconds = kernel_seconds(&self.kernels.timed_names, &p.timed, ticks, period);
        }
        Ok(Some(stats))
    }

    /// Work cut short is an error, never a darker image: an item whose in-kernel loop hit
    /// the engine's iteration cap, or persistent threads that started and never ended their
    /// loop (the driver stopped them: their items were cut short or never taken).
    fn check_loops_ended(&self, words: &[u32]) -> Result<()> {
        let control = &self.program.resolved.control;
        let layout = &self.program.plan.layout_name;
        let capped = words[control.loop_capped as usize];
        if capped > 0 {
            return Err(Error::Runtime(format!(
                "layout '{layout}': {capped} items stopped at the cap of {} iterations of an in-kernel loop: a loop pass never finishes its item",
                self.program.target.max_loop_iterations
            )));
        }
        for (&c, &(started, ended)) in &control.persistent {
            let (started, ended) = (words[started as usize], words[ended as usize]);
            if started != ended {
                let item = &self.program.plan.graph.chains[c].item;
                let driver = if self.gpu.caps_invocation_loops() {
                    "llvmpipe ends every loop of an invocation after 65535 iterations in all"
                } else {
                    "the driver stopped them early (a watchdog or an iteration cap)"
                };
                return Err(Error::Runtime(format!(
                    "layout '{layout}': {} of {started} persistent threads over '{item}' never ended their loop, so their items were cut short or never taken: {driver}; the frames are not kept (a layout of one item per thread, e.g. an 'mk' layout, avoids it)",
                    started - ended
                )));
            }
        }
        Ok(())
    }

    /// An overflowed queue or an operator that met a key out of range is an error.
    fn check_overflows(&self, words: &[u32]) -> Result<()> {
        let control = &self.program.resolved.control;
        let g = &self.program.plan.graph;
        for (&q, &w) in &control.queue_overflow {
            if words[w as usize] > 0 {
                return Err(Error::Runtime(format!(
                    "queue '{}' overflowed by {} items: a pass emits more than the stream's per_call ({}) declares",
                    g.streams[q].name, words[w as usize], g.streams[q].decl.per_call
                )));
            }
        }
        for (o, &w) in &control.op_overflow {
            if words[w as usize] > 0 {
                let op = &g.ops[*o];
                let what = match op.kind {
                    OpKind::Count { .. } => "a key beyond its counts",
                    OpKind::Sort { .. } => {
                        "a workgroup whose subgroups were not all full (the sort ranks by subgroup ballots)"
                    }
                    _ => "a key beyond its offsets or a place beyond its output",
                };
                return Err(Error::Runtime(format!(
                    "operator '{}' ({}) skipped {} elements with {what}",
                    op.name,
                    op.describe(),
                    words[w as usize]
                )));
            }
        }
        Ok(())
    }
}

/// Maps the first `size` bytes of `buffer` (rounded up to 8), waits for `submission` (the
/// last one writing it; later ones go on running), and copies them out.
fn map_buffer(gpu: &Gpu, buffer: &wgpu::Buffer, size: u64, submission: wgpu::SubmissionIndex) -> Result<Vec<u8>> {
    let slice = buffer.slice(0..size.next_multiple_of(8));
    slice.map_async(wgpu::MapMode::Read, |_| {});
    gpu.wait_for(submission)?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| Error::Gpu(format!("mapping a read-back buffer failed: {e}")))?
        .to_vec();
    buffer.unmap();
    Ok(data)
}
