//! The radix sort operator checked against a stable sort on the CPU and timed: a graph whose
//! one step is a `Sort` of host-written keys (and values, or none), over a parameter's number
//! of elements (so one compiled program sorts every length up to its capacity), optionally
//! counted on the GPU.

use super::{Numbers, median, repeat_for};
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Graph;
use crate::ir::ConstValue;
use crate::limits::Target;
use crate::program::{Specialization, compile};
use crate::runtime::{FrameStats, Instance};
use crate::vfs::Vfs;
use std::collections::BTreeMap;
use std::time::Duration;

/// The keys a check sorts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keys {
    /// Random 32-bit keys.
    Random,
    /// One key for every element (the order must not change at all).
    Equal,
    /// Descending, spread over the 32 bits.
    Descending,
    /// Random in the top 4 bits, the other bits 0 (every pass but the last sees one digit).
    HighBits,
}

impl Keys {
    /// Every pattern.
    pub const ALL: [Keys; 4] = [Keys::Random, Keys::Equal, Keys::Descending, Keys::HighBits];

    /// `n` keys of this pattern.
    pub fn draw(self, n: usize, seed: u64) -> Vec<u32> {
        let mut rng = Numbers(seed);
        (0..n)
            .map(|i| match self {
                Keys::Random => rng.next() as u32,
                Keys::Equal => 0x8000_0001,
                Keys::Descending => ((n - 1 - i) as u64 * u32::MAX as u64 / n as u64) as u32,
                Keys::HighBits => rng.next() as u32 & 0xf000_0000,
            })
            .collect()
    }
}

/// What the GPU left in the sort's buffers, and how long it took.
#[derive(Debug, Clone)]
pub struct Sorted {
    /// The keys (as many as were written).
    pub keys: Vec<u32>,
    /// The values (none for a sort of keys only).
    pub values: Option<Vec<u32>>,
    /// GPU seconds of the sort, all its kernels (median of the runs; `None` without
    /// timestamps).
    pub seconds: Option<f64>,
    /// GPU seconds of each kernel (median of the runs), in the order they run.
    pub kernels: Vec<(String, f64)>,
}

/// A compiled sort on a GPU.
pub struct Sorter<'g> {
    instance: Instance<'g>,
    kernels: Vec<String>,
    capacity: u64,
    counted: bool,
    values: bool,
    warm_up: Duration,
}

impl<'g> Sorter<'g> {
    /// A sort of at most `capacity` elements by their low `bits` bits on `gpu` (subgroup
    /// kernels where `target` has subgroups), over a GPU-written count when `counted`, moving
    /// values with the keys.
    pub fn new(gpu: &'g Gpu, target: &Target, capacity: u64, bits: u32, counted: bool) -> Result<Sorter<'g>> {
        Sorter::build(gpu, target, capacity, bits, counted, true)
    }

    /// The same sort of keys alone.
    pub fn keys_only(gpu: &'g Gpu, target: &Target, capacity: u64, bits: u32) -> Result<Sorter<'g>> {
        Sorter::build(gpu, target, capacity, bits, false, false)
    }

    fn build(
        gpu: &'g Gpu,
        target: &Target,
        capacity: u64,
        bits: u32,
        counted: bool,
        values: bool,
    ) -> Result<Sorter<'g>> {
        let text = graph_text(capacity.max(1), bits, counted, values);
        let graph = Graph::from_text(&Vfs::default(), "sort.ron", &text)?;
        let program = compile(
            &graph,
            "sort",
            graph.layout("sort")?,
            &Specialization::default(),
            target,
        )?;
        let kernels = program.ops[0].kernels.iter().map(|(k, _)| k.name.clone()).collect();
        Ok(Sorter {
            instance: Instance::new(gpu, program, &BTreeMap::new())?,
            kernels,
            capacity,
            counted,
            values,
            warm_up: Duration::ZERO,
        })
    }

    /// One sort of the written keys (restored from their snapshot where `restore`), frame
    /// index `run`.
    fn run_once(&mut self, restore: bool, count: u32, run: u32) -> Result<FrameStats> {
        if restore {
            self.instance.restore("keys")?;
            if self.values {
                self.instance.restore("values")?;
            }
        }
        if self.counted {
            self.instance.write("elements", bytemuck::bytes_of(&count))?;
        }
        self.instance.run_frame(run, 0)
    }

    /// The same sorter sorting untimed for `time` before each [`Sorter::sort`]'s timed runs
    /// ([`crate::selfcheck::run`] says why).
    pub fn warmed_up(mut self, time: Duration) -> Sorter<'g> {
        self.warm_up = time;
        self
    }

    /// Writes `keys` and `values` (ignored by a sort of keys only) from the first element,
    /// sorts the first `over` of them (with a counted sorter, the first `count`, at most
    /// `over`), `runs` times (restoring them on the GPU before each, so that the runs follow
    /// one another without host uploads), and reads back as many as were written.
    pub fn sort(&mut self, keys: &[u32], values: &[u32], over: u64, count: u32, runs: u32) -> Result<Sorted> {
        let n = keys.len();
        if (self.values && values.len() != n) || n as u64 > self.capacity || over > n as u64 {
            return Err(Error::Runtime(format!(
                "cannot sort {over} of {n} keys with {} values in a sort of {}",
                values.len(),
                self.capacity
            )));
        }
        self.instance.set_parameter("ELEMENTS", ConstValue::U32(over as u32))?;
        let mut times = Vec::new();
        let mut per_kernel: Vec<Vec<f64>> = vec![Vec::new(); self.kernels.len()];
        if n > 0 {
            self.instance.write("keys", bytemuck::cast_slice(keys))?;
            self.instance.snapshot("keys")?;
            if self.values {
                self.instance.write("values", bytemuck::cast_slice(values))?;
                self.instance.snapshot("values")?;
            }
        }
        let warm_up = self.warm_up;
        repeat_for(warm_up, || self.run_once(n > 0, count, 0).map(drop))?;
        for run in 0..runs.max(1) {
            let stats = self.run_once(n > 0, count, run)?;
            let found: Vec<f64> = self
                .kernels
                .iter()
                .filter_map(|k| stats.kernel_seconds.get(k))
                .copied()
                .collect();
            for (k, name) in self.kernels.iter().enumerate() {
                per_kernel[k].extend(stats.kernel_seconds.get(name));
            }
            if found.len() == self.kernels.len() {
                times.push(found.iter().sum());
            }
        }
        let read = |name: &str| -> Result<Vec<u32>> {
            let mut v: Vec<u32> = bytemuck::pod_collect_to_vec(&self.instance.read(name)?);
            v.truncate(n);
            Ok(v)
        };
        let kernels = self
            .kernels
            .iter()
            .zip(per_kernel)
            .filter_map(|(name, t)| median(t).map(|t| (name.clone(), t)))
            .collect();
        Ok(Sorted {
            keys: read("keys")?,
            values: if self.values { Some(read("values")?) } else { None },
            seconds: median(times),
            kernels,
        })
    }
}

/// The graph of a sort: `ELEMENTS` (a parameter) of `CAPACITY` keys and values (or keys
/// alone).
fn graph_text(capacity: u64, bits: u32, counted: bool, values: bool) -> String {
    let counted = if counted { ", counted: \"elements\"" } else { "" };
    let (moved, outputs) = match values {
        true => (", values: \"values\"", r#""keys", "values""#),
        false => ("", r#""keys""#),
    };
    format!(
        r#"(
    name: "sort",
    description: "stable radix sort of host-written keys and values",
    passes: [Sort(name: "sort", keys: "keys"{moved}, over: "ELEMENTS", bits: {bits}{counted})],
    resources: {{
        "keys": (ty: "u32", count: "CAPACITY"),
        "values": (ty: "u32", count: "CAPACITY"),
        "elements": (ty: "u32"),
    }},
    constants: {{ "CAPACITY": U32({capacity}) }},
    parameters: {{ "ELEMENTS": U32({capacity}) }},
    outputs: [{outputs}],
    layouts: {{ "sort": (kernels: []) }},
    default_layout: "sort",
)
"#
    )
}

/// The first disagreement of `sorted` with a stable sort on the CPU of the first `n` of
/// `keys` (with `values`, unless `sorted` has none) by their low `bits` bits, the rest left as
/// they were.
pub fn compare(keys: &[u32], values: &[u32], n: usize, bits: u32, sorted: &Sorted) -> Option<String> {
    let mask = if bits >= 32 { u32::MAX } else { (1u32 << bits) - 1 };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| keys[i] & mask);
    order.extend(n..keys.len());
    let values_read = sorted.values.as_ref().map_or(keys.len(), Vec::len);
    if sorted.keys.len() != keys.len() || values_read != keys.len() {
        return Some(format!(
            "read back {} keys and {values_read} values, {} were written",
            sorted.keys.len(),
            keys.len()
        ));
    }
    for (place, &i) in order.iter().enumerate() {
        let k = sorted.keys[place];
        let v = sorted.values.as_ref().map_or(values[i], |v| v[place]);
        if k != keys[i] || v != values[i] {
            return Some(format!(
                "place {place} holds key {k:#x} value {v}, the CPU says key {:#x} value {} (of {n} sorted)",
                keys[i], values[i]
            ));
        }
    }
    None
}

/// What one check of the sort found.
#[derive(Debug, Clone)]
pub struct SortReport {
    /// The first disagreement with the CPU, if any.
    pub mismatch: Option<String>,
    /// GPU seconds of the sort (median of the runs).
    pub seconds: Option<f64>,
    /// GPU seconds of each kernel (median of the runs), in the order they run.
    pub kernels: Vec<(String, f64)>,
}

/// One check of the sort: what it sorts and how often.
#[derive(Debug, Clone, Copy)]
pub struct SortCheck {
    /// Elements.
    pub n: u64,
    /// Their keys.
    pub pattern: Keys,
    /// Low bits sorted by.
    pub bits: u32,
    /// Whether values move with the keys (their indices, so that any instability shows).
    pub values: bool,
    /// Timed runs.
    pub runs: u32,
    /// Untimed sorting before them ([`crate::selfcheck::run`] says why).
    pub warm_up: Duration,
}

/// Sorts as `c` says and checks the last run against the CPU.
pub fn check(gpu: &Gpu, target: &Target, c: SortCheck) -> Result<SortReport> {
    let SortCheck {
        n,
        pattern,
        bits,
        values: moved,
        runs,
        warm_up,
    } = c;
    let keys = pattern.draw(n as usize, n ^ 0x50f7);
    let values: Vec<u32> = (0..n as u32).collect();
    let sorter = match moved {
        true => Sorter::new(gpu, target, n, bits, false)?,
        false => Sorter::keys_only(gpu, target, n, bits)?,
    };
    let mut sorter = sorter.warmed_up(warm_up);
    let sorted = sorter.sort(&keys, &values, n, 0, runs)?;
    Ok(SortReport {
        mismatch: compare(&keys, &values, n as usize, bits, &sorted),
        seconds: sorted.seconds,
        kernels: sorted.kernels,
    })
}
