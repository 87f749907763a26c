//! A session: a run compiled and instantiated on one GPU, rendering frame after frame into
//! a progressive accumulation on the GPU.

use crate::run::measure::{Prepared, measure_prepared, prepare};
use crate::run::options::SessionOptions;
use crate::run::scene::LoadedScene;
use anyhow::{Context, Result, anyhow, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::runtime::{IN_FLIGHT, MAX_BATCH};
use lightgraph_engine::{ConstValue, FrameStats, Gpu, Graph, Instance, Program, compile};
use std::collections::BTreeMap;
use std::time::Duration;

/// GPU time of one batch of frames in [`Session::render_for`]: short enough for a live
/// progress line and preview, long enough that recording and reading back stay small.
pub const BATCH_TIME: Duration = Duration::from_millis(100);

/// A per-pixel image: the mean of the frames' estimates and their variance.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Frames accumulated.
    pub frames: u32,
    /// Mean radiance per pixel (row-major, top row first).
    pub mean: Vec<[f32; 3]>,
    /// Sample variance of the per-frame estimates (the squared standard error of the mean is
    /// this over `frames`).
    pub variance: Vec<[f32; 3]>,
}

/// The GPU's progressive sums: per pixel, the sum of the frames' estimates and of their
/// squares.
#[derive(Debug, Clone)]
pub struct Accumulation {
    /// The frame indices summed: sorted, disjoint half-open ranges.
    pub ranges: Vec<(u64, u64)>,
    /// Frames summed.
    pub frames: u32,
    /// Sum of the per-frame estimates (RGB, fourth word unused).
    pub sum: Vec<[f32; 4]>,
    /// Sum of their squares.
    pub sum_sq: Vec<[f32; 4]>,
}

/// A scene rendered by a graph in one layout.
pub struct Session<'g> {
    instance: Instance<'g>,
    /// Options of the session.
    pub options: SessionOptions,
    /// Frames rendered (submitted to the GPU; [`Session::settled`] of them read back).
    pub frames: u32,
    /// Frames whose statistics are in `counters` and `kernel_seconds`: the frames
    /// rendered less those of the batches still in flight.
    pub settled: u32,
    /// Frames of each batch submitted and not yet read back, oldest first.
    in_flight: std::collections::VecDeque<u32>,
    /// Frame index of the session's first frame: a resumed render continues the random
    /// streams where the earlier one stopped instead of repeating them.
    pub first_frame: u32,
    /// The frame indices rendered since [`Session::take_accumulation`] last emptied the GPU
    /// accumulation (what it holds), adjacent ones joined.
    pending: Vec<(u64, u64)>,
    /// Counter totals of the settled frames.
    pub counters: BTreeMap<String, u64>,
    /// GPU time per kernel, summed over the settled frames.
    pub kernel_seconds: BTreeMap<String, f64>,
    /// Loops stopped by the iteration cap (must stay 0).
    pub loops_capped: u64,
}

impl<'g> Session<'g> {
    /// Compiles and instantiates `graph` in its layout called `layout` for `scene`.
    pub fn new(
        gpu: &'g Gpu,
        graph: &Graph,
        layout: &str,
        scene: &LoadedScene,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        // Resolving by name first gives the error that lists the graph's layouts.
        let decl = graph.layout(layout)?.clone();
        Self::with_layout(gpu, graph, layout, decl, scene, options)
    }

    /// Compiles and instantiates `graph` in the layout `decl` (named `layout`). The
    /// graph's measured constants not given in the options are measured first
    /// ([`measure_constants`]).
    pub fn with_layout(
        gpu: &'g Gpu,
        graph: &Graph,
        layout: &str,
        decl: LayoutDecl,
        scene: &LoadedScene,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        let Prepared {
            decl,
            mut spec,
            externals,
        } = prepare(gpu, graph, (layout, decl), scene, &options)?;
        let measured = measure_prepared(gpu, graph, layout, (&decl, &spec, &externals), &options)?;
        spec.constants.extend(measured);
        let program = compile(graph, layout, &decl, &spec, &options.layout.target(gpu))?;
        Self::instantiate(gpu, graph, layout, program, &externals, options)
    }

    /// Instantiates `program`, compiled already for `graph` in the layout `decl` (named
    /// `layout`) on `scene` with `options` (measured constants among them), without compiling
    /// it again: a layout the tuner measured ([`crate::run::Run::take_tuned`]).
    pub(crate) fn of_program(
        gpu: &'g Gpu,
        graph: &Graph,
        (layout, decl): (&str, LayoutDecl),
        program: Program,
        scene: &LoadedScene,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        let Prepared { externals, .. } = prepare(gpu, graph, (layout, decl), scene, &options)?;
        Self::instantiate(gpu, graph, layout, program, &externals, options)
    }

    /// A session of `program` (of `graph` in the layout called `layout`) with the scene's
    /// resources `externals`.
    fn instantiate(
        gpu: &'g Gpu,
        graph: &Graph,
        layout: &str,
        program: Program,
        externals: &BTreeMap<String, Vec<u8>>,
        options: SessionOptions,
    ) -> Result<Session<'g>> {
        let instance = Instance::new(gpu, program, externals)
            .with_context(|| format!("instantiating graph '{}' in layout '{layout}'", graph.name))?;
        Ok(Session {
            instance,
            options,
            frames: 0,
            settled: 0,
            in_flight: Default::default(),
            first_frame: 0,
            pending: Vec::new(),
            counters: BTreeMap::new(),
            kernel_seconds: BTreeMap::new(),
            loops_capped: 0,
        })
    }

    /// The compiled program.
    pub fn program(&self) -> &Program {
        self.instance.program()
    }

    /// Renders one more frame (or [`Session::frames_at_once`] frames where the graph runs
    /// several as one).
    pub fn render_frame(&mut self) -> Result<FrameStats> {
        self.render_frames(self.frames_at_once())
    }

    /// Frames the GPU renders as one (the graph's `FRAMES_AT_ONCE`, passes/film.ron; 1 for a
    /// graph without it): batches and frame indices then come in multiples of it.
    pub fn frames_at_once(&self) -> u32 {
        match self.instance.program().constants().get("FRAMES_AT_ONCE") {
            Some(ConstValue::U32(n)) => (*n).max(1),
            _ => 1,
        }
    }

    /// Checks that frames `first .. first + count` are whole groups of the frames the GPU
    /// renders as one ([`Session::frames_at_once`]).
    pub fn check_frames(&self, first: u32, count: u32) -> Result<()> {
        let at_once = self.frames_at_once();
        if !count.is_multiple_of(at_once) || !first.is_multiple_of(at_once) {
            bail!(
                "frames {first} to {} do not start and end at multiples of FRAMES_AT_ONCE = {at_once} \
                 (the frames the GPU renders as one): render and resume a multiple of {at_once} frames",
                first as u64 + count as u64
            );
        }
        Ok(())
    }

    /// Goes on at frame index `first` instead of the next one: frames claimed out of order
    /// (by several GPUs or ranks sharing a run). The accumulation records which frames it holds.
    pub fn jump_to(&mut self, first: u32) -> Result<()> {
        self.first_frame = first
            .checked_sub(self.frames)
            .ok_or_else(|| anyhow!("frame {first} is before the {} frames rendered", self.frames))?;
        Ok(())
    }

    /// Renders `count` more frames (at most [`MAX_BATCH`] times [`Session::frames_at_once`],
    /// a multiple of it) recorded together, with one
    /// read-back of statistics, and waits for them (and any batch still in flight); returns
    /// the statistics of the frames it waited for.
    pub fn render_frames(&mut self, count: u32) -> Result<FrameStats> {
        self.submit(count)?;
        self.settle()
    }

    /// Renders toward a budget, keeping the GPU busy: submits a batch of about
    /// [`BATCH_TIME`] of frames (at most `max`, and no more than fills the `left` time of a
    /// timed run, counting the batch still running), then reads back the batch before it,
    /// so that the host records and reads back while the GPU runs. Returns the statistics of
    /// the batches read back (empty when none finished; [`Session::settle`] reads the rest).
    /// Until a frame's GPU time is known (always, on an adapter without timestamp queries) it
    /// renders one frame and waits for it. Frames come in multiples of
    /// [`Session::frames_at_once`].
    pub fn render_for(&mut self, left: Option<Duration>, max: u32) -> Result<FrameStats> {
        let at_once = self.frames_at_once();
        let per_frame = self.kernel_seconds.values().sum::<f64>() / self.settled.max(1) as f64;
        if self.settled == 0 || per_frame <= 0.0 {
            return self.render_frames(max.min(at_once));
        }
        let queued = self.in_flight.iter().sum::<u32>() as f64 * per_frame;
        let room = left.map_or(f64::INFINITY, |t| t.as_secs_f64() - queued);
        let most = (MAX_BATCH * at_once) as f64;
        let wanted = (room.min(BATCH_TIME.as_secs_f64()) / per_frame).clamp(0.0, most) as u32;
        let count = match wanted.min(max) / at_once * at_once {
            // A timed run with less than a frame left still renders one, unless the batch in
            // flight ends it.
            0 if self.in_flight.is_empty() => max.min(at_once),
            n => n,
        };
        match count {
            0 => self.settle(),
            _ => self.render_frames_behind(count),
        }
    }

    /// Submits `count` more frames (as [`Session::render_frames`]) and reads back the batches
    /// before them, leaving this one running, so that the host records the next batch while
    /// the GPU renders; returns the statistics of the batches read back
    /// ([`Session::settle`] reads the rest).
    pub fn render_frames_behind(&mut self, count: u32) -> Result<FrameStats> {
        self.submit(count)?;
        let mut stats = FrameStats::default();
        while self.in_flight.len() > 1 {
            stats.add(&self.collect()?);
        }
        Ok(stats)
    }

    /// Reads back every batch still in flight (waiting for them); returns their statistics.
    /// Counters and GPU times cover every frame rendered after it.
    pub fn settle(&mut self) -> Result<FrameStats> {
        let mut stats = FrameStats::default();
        while !self.in_flight.is_empty() {
            stats.add(&self.collect()?);
        }
        Ok(stats)
    }

    /// Submits `count` frames (at most [`MAX_BATCH`] of the GPU's, each
    /// [`Session::frames_at_once`] frames) as one batch; at most one other batch stays in
    /// flight (an older one is read back first).
    fn submit(&mut self, count: u32) -> Result<()> {
        if self.first_frame as u64 + self.frames as u64 + count as u64 > u32::MAX as u64 {
            bail!("the frame index would pass 2^32; continue with another seed");
        }
        let first = self.first_frame + self.frames;
        self.check_frames(first, count)?;
        let at_once = self.frames_at_once();
        while self.in_flight.len() >= IN_FLIGHT {
            self.collect()?;
        }
        self.instance
            .submit_frames(first / at_once, count / at_once, self.options.seed)?;
        self.in_flight.push_back(count);
        self.frames += count;
        let range = (first as u64, first as u64 + count as u64);
        match self.pending.last_mut() {
            Some(last) if last.1 == range.0 => last.1 = range.1,
            _ => self.pending.push(range),
        }
        Ok(())
    }

    /// Waits for the oldest batch in flight and adds its statistics to the session's.
    fn collect(&mut self) -> Result<FrameStats> {
        let stats = self
            .instance
            .collect_frames()?
            .ok_or_else(|| anyhow!("no batch of frames in flight"))?;
        let count = self.in_flight.pop_front().expect("a batch in flight");
        self.settled += count;
        stats.add_to(&mut self.counters, &mut self.kernel_seconds);
        self.loops_capped += stats.loops_capped as u64;
        Ok(stats)
    }

    /// GPU memory of the session: the buffers the layout allocates (transient ones sharing
    /// memory) and the scene data.
    pub fn memory_bytes(&self) -> u64 {
        let program = self.instance.program();
        let external: u64 = program
            .plan
            .graph
            .resources
            .iter()
            .zip(&program.resolved.sizes)
            .filter_map(|(r, size)| {
                self.instance
                    .external_count(&r.name)
                    .map(|n| n * size.element_bytes as u64)
            })
            .sum();
        program.peak_bytes() + external
    }

    /// Rays traced so far (primary, extension and shadow counters of the graph).
    pub fn rays(&self) -> u64 {
        self.counters
            .iter()
            .filter(|(k, _)| k.starts_with("rays_"))
            .map(|(_, v)| v)
            .sum()
    }

    /// Samples per pixel accumulated so far.
    pub fn samples_per_pixel(&self) -> u64 {
        self.frames as u64 * self.options.samples_per_frame as u64
    }

    /// Reads the GPU accumulation: the number of frames in it, the per-pixel sums of the
    /// frames' estimates and the sums of their squares (RGB and an unused fourth word).
    pub fn accumulation(&self) -> Result<Accumulation> {
        Ok(Accumulation {
            ranges: self.pending.clone(),
            frames: self.pending.iter().map(|r| (r.1 - r.0) as u32).sum(),
            sum: bytemuck::pod_collect_to_vec(&self.instance.read("accum")?),
            sum_sq: bytemuck::pod_collect_to_vec(&self.instance.read("accum_sq")?),
        })
    }

    /// Reads the GPU accumulation and empties it, so a host accumulator (in f64) can take
    /// the sums over and the f32 sums on the GPU stay short.
    pub fn take_accumulation(&mut self) -> Result<Accumulation> {
        self.settle()?;
        let taken = self.accumulation()?;
        for name in ["accum", "accum_comp", "accum_sq"] {
            self.instance.clear(name)?;
        }
        self.pending.clear();
        Ok(taken)
    }

    /// The sums of the per-frame estimates of the light a FILM_BIASED graph's biased technique
    /// added (its film's second channel, passes/film.ron) since the last take, read and
    /// emptied; `None` for a graph without the channel. Call it right after
    /// [`Session::take_accumulation`], which settles the frames.
    pub fn take_biased(&mut self) -> Result<Option<Vec<[f32; 4]>>> {
        let constants = &self.instance.program().resolved.constants;
        if constants.get("FILM_BIASED").is_none_or(|v| v.as_f64() == 0.0) {
            return Ok(None);
        }
        let sums = bytemuck::pod_collect_to_vec(&self.instance.read("accum_biased")?);
        self.instance.clear("accum_biased")?;
        Ok(Some(sums))
    }

    /// Renders a frame and throws it away, leaving the session as new (frame 0 next, nothing
    /// accumulated or counted) with every pipeline used once: a driver that compiles a
    /// pipeline at its first dispatch (lavapipe) does it here, before a timed run's clock.
    pub fn warm_up(&mut self) -> Result<()> {
        self.render_frame()?;
        self.take_accumulation()?;
        self.frames = 0;
        self.settled = 0;
        self.counters.clear();
        self.kernel_seconds.clear();
        self.loops_capped = 0;
        Ok(())
    }

    /// The accumulated image (reads the GPU accumulation).
    pub fn image(&self) -> Result<Image> {
        let (w, h) = (self.options.width, self.options.height);
        let Accumulation {
            frames,
            sum,
            sum_sq: sq,
            ..
        } = self.accumulation()?;
        let n = frames.max(1) as f64;
        let mut mean = Vec::with_capacity(sum.len());
        let mut variance = Vec::with_capacity(sum.len());
        for (s, q) in sum.iter().zip(&sq) {
            let m = [0, 1, 2].map(|c| s[c] as f64 / n);
            mean.push(m.map(|v| v as f32));
            variance.push([0, 1, 2].map(|c| {
                if n > 1.0 {
                    (((q[c] as f64) / n - m[c] * m[c]) * n / (n - 1.0)).max(0.0) as f32
                } else {
                    0.0
                }
            }));
        }
        Ok(Image {
            width: w,
            height: h,
            frames,
            mean,
            variance,
        })
    }
}
