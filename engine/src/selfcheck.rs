//! The engine's collective operators checked against the CPU and timed: an exclusive scan of
//! `n` words and one of `n` `f32` weights (against an `f64` sum), and a counting sort (clear,
//! count, scan of the bucket counts, scatter) of `n` 12-byte elements into `buckets` buckets,
//! whose 48-byte elements (a cache vertex's size, moved as 16-byte vectors) a second scatter
//! places likewise, and a third scatter places the elements' indices (the sorting
//! permutation), through which a gather reads the 48-byte elements into place again, all from
//! one graph run on any adapter; the radix sort in [`sort`]. The tests run them at the sizes
//! lavapipe allows; `lightgraph operators` runs them on a GPU.

pub mod sort;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::graph::Graph;
use crate::ir::ConstValue;
use crate::limits::Target;
use crate::program::{Specialization, compile};
use crate::runtime::Instance;
use crate::vfs::{Layer, Vfs};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The graph: every step an operator, the data written by the host.
const GRAPH: &str = r#"// Exclusive scans (u32, f32) and counting sort of host-written data (the engine's self-check).
(
    name: "operators",
    description: "exclusive scans of `values` and `weights`; counting sort of `payload` by `keys` into `sorted`",
    library: ["operators.wgsl"],
    passes: [
        Scan(name: "scan", input: "values", output: "sums", over: "N"),
        Clear(name: "clear_counts", buffer: "counts"),
        Count(name: "count", keys: "keys", counts: "counts", slots: "slots", over: "N"),
        Scan(name: "bucket_starts", input: "counts", output: "starts", over: "BUCKETS"),
        Scatter(name: "scatter", keys: "keys", slots: "slots", offsets: "starts", input: "payload", output: "sorted", over: "N"),
        Scatter(name: "scatter_wide", keys: "keys", slots: "slots", offsets: "starts", input: "wide", output: "wide_sorted", over: "N"),
        Scatter(name: "scatter_index", keys: "keys", slots: "slots", offsets: "starts", output: "order", over: "N"),
        Gather(name: "gather_wide", indices: "order", input: "wide", output: "wide_gathered", over: "N"),
        Scan(name: "scan_f32", input: "weights", output: "weight_sums", over: "N"),
    ],
    resources: {
        "values": (ty: "u32", count: "max(N, 1)"),
        "sums": (ty: "u32", count: "max(N, 1)"),
        "keys": (ty: "u32", count: "max(N, 1)"),
        "counts": (ty: "atomic<u32>", count: "BUCKETS"),
        "slots": (ty: "u32", count: "max(N, 1)"),
        "starts": (ty: "u32", count: "BUCKETS"),
        "payload": (ty: "Payload", count: "max(N, 1)"),
        "sorted": (ty: "Payload", count: "max(N, 1)"),
        "wide": (ty: "Wide", count: "max(N, 1)"),
        "wide_sorted": (ty: "Wide", count: "max(N, 1)"),
        "order": (ty: "u32", count: "max(N, 1)"),
        "wide_gathered": (ty: "Wide", count: "max(N, 1)"),
        "weights": (ty: "f32", count: "max(N, 1)"),
        "weight_sums": (ty: "f32", count: "max(N, 1)"),
    },
    constants: { "N": U32(1), "BUCKETS": U32(1) },
    outputs: ["sums", "slots", "starts", "sorted", "wide_sorted", "order", "wide_gathered", "weight_sums"],
    layouts: { "operators": (kernels: []) },
    default_layout: "operators",
)
"#;

const FILES: &[(&str, &str)] = &[
    ("operators.ron", GRAPH),
    (
        "operators.wgsl",
        "// A 12-byte element of the counting sort, and a 48-byte one.\nstruct Payload { index: u32, key: u32, check: u32 }\nstruct Wide { words: array<vec4<u32>, 3> }\n",
    ),
];

/// How the inputs are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// Random values; random keys; random weights in [0, 4), one in about a thousand in
    /// [2^16, 2^17).
    Random,
    /// Every value and weight 1; every key the same (one bucket holds every element).
    Equal,
    /// One value holds the whole sum; every key the last bucket; every weight 0.25 but one of
    /// 2^100 (which rounds away everything added to it after).
    Concentrated,
}

impl Pattern {
    /// Every pattern.
    pub const ALL: [Pattern; 3] = [Pattern::Random, Pattern::Equal, Pattern::Concentrated];
}

/// What one check found.
#[derive(Debug, Clone)]
pub struct Report {
    /// Elements.
    pub n: u64,
    /// Buckets.
    pub buckets: u64,
    /// The inputs.
    pub pattern: Pattern,
    /// The first disagreement with the CPU, if any.
    pub mismatch: Option<String>,
    /// GPU seconds of the scan, per run (median of the runs).
    pub scan_seconds: Option<f64>,
    /// GPU seconds of the `f32` scan, per run (median of the runs).
    pub f32_scan_seconds: Option<f64>,
    /// GPU seconds of the counting sort (clear, count, scan, scatter), per run (median).
    pub sort_seconds: Option<f64>,
    /// GPU seconds of each kernel (median of the runs), in the order they run.
    pub kernels: Vec<(String, f64)>,
}

/// SplitMix64: seeded, well-mixed 64-bit numbers.
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }
}

/// The inputs of a check.
#[derive(Debug, Clone)]
pub struct Inputs {
    /// The scan's words.
    pub values: Vec<u32>,
    /// The sort's keys.
    pub keys: Vec<u32>,
    /// The `f32` scan's weights.
    pub weights: Vec<f32>,
}

impl Inputs {
    /// `n` elements of `pattern`, keys below `buckets`.
    pub fn draw(n: usize, buckets: u64, pattern: Pattern, seed: u64) -> Inputs {
        let (values, keys) = words(n, buckets, pattern, seed);
        let weights = weights(n, pattern, seed ^ 0xf32);
        Inputs { values, keys, weights }
    }
}

/// The scan's input and the sort's keys for `pattern`.
fn words(n: usize, buckets: u64, pattern: Pattern, seed: u64) -> (Vec<u32>, Vec<u32>) {
    let mut rng = Numbers(seed);
    match pattern {
        Pattern::Random => (
            (0..n).map(|_| rng.next() as u32).collect(),
            (0..n).map(|_| (rng.next() % buckets) as u32).collect(),
        ),
        Pattern::Equal => (vec![1; n], vec![(buckets / 2) as u32; n]),
        Pattern::Concentrated => {
            let mut values = vec![0; n];
            if n > 0 {
                values[n / 2] = 0xdead_beef;
            }
            (values, vec![(buckets - 1) as u32; n])
        }
    }
}

/// The `f32` scan's weights for `pattern`: non-negative (see [`F32_SCAN_RELATIVE`]).
fn weights(n: usize, pattern: Pattern, seed: u64) -> Vec<f32> {
    let mut rng = Numbers(seed);
    // 24 random bits: a uniform f32 in [0, 1), exactly.
    let mut unit = move || (rng.next() >> 40) as f32 / (1u32 << 24) as f32;
    match pattern {
        Pattern::Random => (0..n)
            .map(|_| match unit() < 1e-3 {
                true => 65536.0 * (1.0 + unit()),
                false => 4.0 * unit(),
            })
            .collect(),
        Pattern::Equal => vec![1.0; n],
        Pattern::Concentrated => {
            let mut w = vec![0.25; n];
            if n > 0 {
                w[n / 2] = 2f32.powi(100);
            }
            w
        }
    }
}

/// The tolerance of the `f32` scan relative to the exact sum, for non-negative weights. The
/// engine adds in its tree's order, so every weight reaches an output through a chain of
/// roundings: per level, a thread's run (at most 16), a workgroup tree (8) or a subgroup sum
/// and the loop over the subgroups' sums, the tile's offset; the checks take at most three
/// levels, fewer than 256 roundings in all. Each rounding of a sum of non-negative values
/// errs by at most 2^-24 of it, so an output errs by at most 256 * 2^-24 (1.5e-5) of the
/// exact sum (in practice far less: the errors partly cancel). No absolute term is needed:
/// the sum of a zero prefix of non-negative weights is exactly 0.
pub const F32_SCAN_RELATIVE: f64 = 256.0 / (1u32 << 24) as f64;

/// Checks the `f32` scan's `sums` of `weights` against an `f64` sum, to [`F32_SCAN_RELATIVE`].
fn compare_weights(weights: &[f32], sums: &[f32]) -> Option<String> {
    let mut exact = 0f64;
    for (i, (&w, &s)) in weights.iter().zip(sums).enumerate() {
        let tolerance = F32_SCAN_RELATIVE * exact;
        let error = (s as f64 - exact).abs();
        if error > tolerance || error.is_nan() {
            return Some(format!(
                "f32 scan: sum before element {i} is {s}, the CPU (f64) says {exact}, beyond {tolerance:e}"
            ));
        }
        exact += w as f64;
    }
    None
}

/// Checks the GPU's outputs against the CPU: the scans' sums, the bucket starts, each
/// element at its bucket's start plus its slot, and each bucket's slots all different.
fn compare(inputs: &Inputs, buckets: u64, out: &Outputs) -> Option<String> {
    compare_words(&inputs.values, &inputs.keys, buckets, out)
        .or_else(|| compare_weights(&inputs.weights, &out.weight_sums))
}

/// [`compare`] of the `u32` scan and the counting sort.
fn compare_words(values: &[u32], keys: &[u32], buckets: u64, out: &Outputs) -> Option<String> {
    let (sums, slots, starts, sorted) = (&out.sums, &out.slots, &out.starts, &out.sorted);
    let mut run = 0u32;
    for (i, (&v, &s)) in values.iter().zip(sums).enumerate() {
        if s != run {
            return Some(format!("scan: sum before element {i} is {s}, the CPU says {run}"));
        }
        run = run.wrapping_add(v);
    }
    let mut counts = vec![0u32; buckets as usize];
    for &k in keys {
        counts[k as usize] += 1;
    }
    let mut start = 0u32;
    for (b, (&c, &s)) in counts.iter().zip(starts).enumerate() {
        if s != start {
            return Some(format!("sort: bucket {b} starts at {s}, the CPU says {start}"));
        }
        start += c;
    }
    let mut taken = vec![false; keys.len()];
    for (i, &k) in keys.iter().enumerate() {
        let slot = slots[i];
        if slot >= counts[k as usize] {
            return Some(format!(
                "sort: element {i} has slot {slot} in bucket {k} of {}",
                counts[k as usize]
            ));
        }
        let place = (starts[k as usize] + slot) as usize;
        if std::mem::replace(&mut taken[place], true) {
            return Some(format!("sort: two elements of bucket {k} took place {place}"));
        }
        let want = element(i, k);
        if sorted[place] != want {
            return Some(format!(
                "sort: place {place} holds {:?}, element {i} is {want:?}",
                sorted[place]
            ));
        }
        let want = wide_element(i, k);
        if out.wide_sorted[place] != want {
            return Some(format!(
                "sort of 48-byte elements: place {place} holds {:?}, element {i} is {want:?}",
                out.wide_sorted[place]
            ));
        }
        if out.order[place] != i as u32 {
            return Some(format!(
                "sort of indices: place {place} holds {}, element {i} is there",
                out.order[place]
            ));
        }
        if out.wide_gathered[place] != want {
            return Some(format!(
                "gather through the sorted indices: place {place} holds {:?}, element {i} is {want:?}",
                out.wide_gathered[place]
            ));
        }
    }
    None
}

/// Median of a list of seconds.
/// Calls `f` again and again until `time` has passed (not at all for zero): untimed runs that
/// bring an idle GPU's clock up before timed ones.
fn repeat_for(time: Duration, mut f: impl FnMut() -> Result<()>) -> Result<()> {
    let start = Instant::now();
    while start.elapsed() < time {
        f()?;
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

/// What the GPU produced.
pub struct Outputs {
    /// The scan's sums.
    pub sums: Vec<u32>,
    /// Each element's slot in its bucket.
    pub slots: Vec<u32>,
    /// Each bucket's first place.
    pub starts: Vec<u32>,
    /// The sorted elements.
    pub sorted: Vec<[u32; 3]>,
    /// The sorted 48-byte elements.
    pub wide_sorted: Vec<[u32; 12]>,
    /// Each place's element index (the sorting permutation).
    pub order: Vec<u32>,
    /// The 48-byte elements gathered through `order`.
    pub wide_gathered: Vec<[u32; 12]>,
    /// The `f32` scan's sums.
    pub weight_sums: Vec<f32>,
    /// GPU seconds of the scan (median of the runs; `None` without timestamps).
    pub scan_seconds: Option<f64>,
    /// GPU seconds of the `f32` scan (median of the runs).
    pub f32_scan_seconds: Option<f64>,
    /// GPU seconds of the counting sort: clear, count, scan, scatter (median of the runs).
    pub sort_seconds: Option<f64>,
    /// GPU seconds of each kernel (median of the runs), in the order they run.
    pub kernels: Vec<(String, f64)>,
}

/// Runs the scans of the values and weights of `inputs` and the counting sort of its elements
/// by their keys into `buckets` buckets on `gpu` (with subgroup kernels when `target` has
/// subgroups), `runs` times, after running them untimed for `warm_up`: a GPU that idled runs
/// its first tenth of a second or so at a fraction of its clock (an H200's SM clock went from
/// 345 to 1980 MHz within 0.1-0.2 s of load), which made every instance after a pause of CPU
/// work 3.5x slower than the first (docs/performance.md, "Operators run the same every time").
pub fn run(gpu: &Gpu, target: &Target, inputs: &Inputs, buckets: u64, runs: u32, warm_up: Duration) -> Result<Outputs> {
    let Inputs { values, keys, weights } = inputs;
    let n = values.len();
    let lengths_differ = keys.len() != n || weights.len() != n;
    if buckets == 0 || lengths_differ || n as u64 > u32::MAX as u64 || buckets > u32::MAX as u64 {
        return Err(Error::Runtime(format!(
            "cannot sort {n} elements into {buckets} buckets"
        )));
    }
    let vfs = Vfs::new(vec![Layer::Embedded(FILES)]);
    let graph = Graph::load(&vfs, "operators.ron")?;
    let spec = Specialization {
        constants: BTreeMap::from([
            ("N".to_string(), ConstValue::U32(n as u32)),
            ("BUCKETS".to_string(), ConstValue::U32(buckets as u32)),
        ]),
        ..Default::default()
    };
    let program = compile(&graph, "operators", graph.layout("operators")?, &spec, target)?;
    let op_kernels: Vec<Vec<String>> = program
        .ops
        .iter()
        .map(|op| op.kernels.iter().map(|(k, _)| k.name.clone()).collect())
        .collect();
    let mut instance = Instance::new(gpu, program, &BTreeMap::new())?;
    let payload: Vec<[u32; 3]> = keys.iter().enumerate().map(|(i, &k)| element(i, k)).collect();
    let wide: Vec<[u32; 12]> = keys.iter().enumerate().map(|(i, &k)| wide_element(i, k)).collect();
    if n > 0 {
        instance.write("values", bytemuck::cast_slice(values))?;
        instance.write("keys", bytemuck::cast_slice(keys))?;
        instance.write("payload", bytemuck::cast_slice(&payload))?;
        instance.write("wide", bytemuck::cast_slice(&wide))?;
        instance.write("weights", bytemuck::cast_slice(weights))?;
    }
    repeat_for(warm_up, || instance.run_frame(0, 0).map(drop))?;
    let (mut scan, mut sort, mut f32_scan) = (Vec::new(), Vec::new(), Vec::new());
    let mut per_kernel: Vec<Vec<f64>> = vec![Vec::new(); op_kernels.iter().flatten().count()];
    for run in 0..runs.max(1) {
        let stats = instance.run_frame(run, 0)?;
        for (k, name) in op_kernels.iter().flatten().enumerate() {
            per_kernel[k].extend(stats.kernel_seconds.get(name));
        }
        let seconds = |ops: &[Vec<String>]| -> Option<f64> {
            let names: Vec<&String> = ops.iter().flatten().collect();
            let found: Vec<f64> = names
                .iter()
                .filter_map(|k| stats.kernel_seconds.get(*k))
                .copied()
                .collect();
            (found.len() == names.len()).then(|| found.iter().sum())
        };
        scan.extend(seconds(&op_kernels[..1]));
        sort.extend(seconds(&op_kernels[1..5]));
        f32_scan.extend(seconds(&op_kernels[8..]));
    }
    let starts: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("starts")?);
    let kernels = op_kernels
        .iter()
        .flatten()
        .zip(per_kernel)
        .filter_map(|(name, times)| median(times).map(|t| (name.clone(), t)))
        .collect();
    Ok(Outputs {
        sums: first_elements(&instance, "sums", n)?,
        slots: first_elements(&instance, "slots", n)?,
        starts,
        sorted: first_elements(&instance, "sorted", n)?,
        wide_sorted: first_elements(&instance, "wide_sorted", n)?,
        order: first_elements(&instance, "order", n)?,
        wide_gathered: first_elements(&instance, "wide_gathered", n)?,
        weight_sums: first_elements(&instance, "weight_sums", n)?,
        scan_seconds: median(scan),
        f32_scan_seconds: median(f32_scan),
        sort_seconds: median(sort),
        kernels,
    })
}

/// The first `n` elements of buffer `name` (buffers hold at least one element).
fn first_elements<T: bytemuck::Pod>(instance: &Instance, name: &str, n: usize) -> Result<Vec<T>> {
    let mut out: Vec<T> = bytemuck::pod_collect_to_vec(&instance.read(name)?);
    out.truncate(n);
    Ok(out)
}

/// The element the sort carries for element `i` with key `k`.
fn element(i: usize, k: u32) -> [u32; 3] {
    [i as u32, k, (i as u32) ^ k.rotate_left(16)]
}

/// The 48-byte element the second scatter carries for element `i` with key `k`.
fn wide_element(i: usize, k: u32) -> [u32; 12] {
    std::array::from_fn(|w| (i as u32).wrapping_mul(12).wrapping_add(w as u32) ^ k.rotate_left(w as u32))
}

/// Runs the scan and the counting sort of `n` elements drawn by `pattern` into `buckets`
/// buckets, `runs` times after `warm_up` ([`run`]), and checks the last run against the CPU.
pub fn check(
    gpu: &Gpu,
    target: &Target,
    n: u64,
    buckets: u64,
    pattern: Pattern,
    runs: u32,
    warm_up: Duration,
) -> Result<Report> {
    let inputs = Inputs::draw(n as usize, buckets.max(1), pattern, n ^ 0x5eed);
    let out = run(gpu, target, &inputs, buckets, runs, warm_up)?;
    let mismatch = compare(&inputs, buckets, &out);
    Ok(Report {
        n,
        buckets,
        pattern,
        mismatch,
        scan_seconds: out.scan_seconds,
        f32_scan_seconds: out.f32_scan_seconds,
        sort_seconds: out.sort_seconds,
        kernels: out.kernels,
    })
}
