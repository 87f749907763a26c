//! The kernels of the `Sort` operator: a stable LSD radix sort of `u32` keys carrying `u32`
//! values, 4 bits a pass. Each pass counts the digits of every tile of [`SORT_TILE`] elements
//! into histograms stored digit-major (digit `d` of tile `t` at `d * tiles + t`), so that one
//! exclusive scan of them (the scan operator's kernels) gives each tile the first place of
//! each of its digits; then each tile ranks its elements by digit (counts per thread, a
//! workgroup scan of them, ties in element order), reorders them in workgroup memory and
//! writes them to their places. Keys and values go back and forth between the operator's
//! buffers and two scratch buffers, copied back at the end when the passes are odd. No kernel
//! waits on another workgroup, so the sort needs no forward-progress guarantee.

use crate::ids::OpId;
use crate::limits::WORKGROUP;
use crate::resolve::{BufferRef, Resolved};
use crate::scan::{Groups, Module, OpKernel, Scan, element_entry};
use crate::scratch::{DIGIT_BITS, HISTOGRAMS, KEYS, PARTIALS, RADIX, SORT_ITEMS, SORT_TILE, VALUES};
use std::fmt::Write;

/// Passes of a sort by the low `bits` bits.
pub fn passes(bits: u32) -> u32 {
    bits.div_ceil(DIGIT_BITS)
}

/// A sort to generate.
pub(crate) struct Sort<'a> {
    /// The operator.
    pub o: OpId,
    /// Its keys.
    pub keys: &'a str,
    /// Its values.
    pub values: &'a str,
    /// Low bits sorted by.
    pub bits: u32,
    /// The resource counting its elements on the GPU.
    pub counted: Option<&'a str>,
    /// Whether to use subgroup operations.
    pub subgroups: bool,
    /// Elements per thread of the histogram scans.
    pub items: u32,
}

impl Sort<'_> {
    /// The kernels: per pass, the digit histograms, their scan and the scatter; then the copy
    /// back when the last pass wrote the scratch.
    pub fn kernels(&self, prefix: &str, resolved: &Resolved) -> Vec<OpKernel> {
        let levels = resolved.op_scratch[&self.o].len() - PARTIALS;
        let operand = [
            BufferRef::Resource(self.keys.to_string()),
            BufferRef::Resource(self.values.to_string()),
        ];
        let scratch = [BufferRef::Scratch(self.o, KEYS), BufferRef::Scratch(self.o, VALUES)];
        let tiles = Groups::elements(SORT_TILE);
        let mut out = Vec::new();
        for p in 0..passes(self.bits) {
            let (src, dst) = match p % 2 {
                0 => (&operand, &scratch),
                _ => (&scratch, &operand),
            };
            let shift = p * DIGIT_BITS;
            let mask = (1u32 << (self.bits - shift).min(DIGIT_BITS)) - 1;
            let mut m = self.module(shift, mask);
            m.bind("lg_src", "array<u32>", src[0].clone());
            m.bind("lg_hist", "array<u32>", BufferRef::Scratch(self.o, HISTOGRAMS));
            let name = format!("{prefix}_digits{p}");
            m.text.push_str(&digits_entry(&name));
            out.push(m.finish(name, tiles));
            out.extend(self.scan(levels).kernels(&format!("{prefix}_scan{p}")));
            let mut m = self.module(shift, mask);
            m.bind("lg_src_keys", "array<u32>", src[0].clone());
            m.bind("lg_src_values", "array<u32>", src[1].clone());
            m.bind("lg_dst_keys", "array<u32>", dst[0].clone());
            m.bind("lg_dst_values", "array<u32>", dst[1].clone());
            m.bind("lg_hist", "array<u32>", BufferRef::Scratch(self.o, HISTOGRAMS));
            let name = format!("{prefix}_scatter{p}");
            m.text.push_str(&scatter_entry(&name, self.subgroups));
            out.push(m.finish(name, tiles));
        }
        if passes(self.bits) % 2 == 1 {
            out.push(self.copy_back(prefix, &operand, &scratch));
        }
        out
    }

    /// The exclusive scan of the histograms, in place, with `levels` of partial sums.
    fn scan(&self, levels: usize) -> Scan<'_> {
        let histograms = BufferRef::Scratch(self.o, HISTOGRAMS);
        Scan {
            o: self.o,
            element: "u32",
            input: histograms.clone(),
            output: histograms,
            partials: PARTIALS,
            levels,
            length: format!("{RADIX}u * ((lg_n() + {SORT_TILE}u - 1u) / {SORT_TILE}u)"),
            per_tile: Some((SORT_TILE, RADIX)),
            counted: self.counted,
            subgroups: self.subgroups,
            items: self.items,
        }
    }

    /// A pass's module: its digit and the tile's size.
    fn module(&self, shift: u32, mask: u32) -> Module {
        let mut m = Module::new(false);
        m.element_count(self.counted);
        let _ = write!(
            m.text,
            "const LG_WG: u32 = {WORKGROUP}u;\nconst LG_ITEMS: u32 = {SORT_ITEMS}u;\nconst LG_TILE: u32 = {SORT_TILE}u;\nconst LG_RADIX: u32 = {RADIX}u;\nconst LG_PADDED: u32 = {};\n\
             // This pass's digit of a key.\n\
             fn lg_digit(key: u32) -> u32 {{ return (key >> {shift}u) & {mask}u; }}\n",
            SORT_TILE + SORT_TILE / 32 + 1
        );
        m
    }

    /// The copy of the sorted keys and values from the scratch into the operator's buffers.
    fn copy_back(&self, prefix: &str, operand: &[BufferRef; 2], scratch: &[BufferRef; 2]) -> OpKernel {
        let mut m = Module::new(false);
        m.bind("lg_src_keys", "array<u32>", scratch[0].clone());
        m.bind("lg_src_values", "array<u32>", scratch[1].clone());
        m.bind("lg_keys", "array<u32>", operand[0].clone());
        m.bind("lg_values", "array<u32>", operand[1].clone());
        m.element_count(self.counted);
        let name = format!("{prefix}_copy");
        let _ = write!(
            m.text,
            "{}    if (i < lg_n()) {{\n        lg_keys[i] = lg_src_keys[i];\n        lg_values[i] = lg_src_values[i];\n    }}\n}}\n",
            element_entry(&name)
        );
        m.finish(name, Groups::elements(WORKGROUP as u64))
    }
}

/// The digit histogram of each tile, digit-major.
fn digits_entry(name: &str) -> String {
    format!(
        "var<workgroup> lg_bins: array<atomic<u32>, {RADIX}>;
@compute @workgroup_size({WORKGROUP})
fn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {{
    let tile = wid.y * nwg.x + wid.x;
    let n = lg_n();
    if (lid < LG_RADIX) {{ atomicStore(&lg_bins[lid], 0u); }}
    workgroupBarrier();
    let base = tile * LG_TILE;
    for (var j = 0u; j < LG_ITEMS; j += 1u) {{
        let i = base + j * LG_WG + lid;
        if (i < n) {{ atomicAdd(&lg_bins[lg_digit(lg_src[i])], 1u); }}
    }}
    workgroupBarrier();
    let tiles = (n + LG_TILE - 1u) / LG_TILE;
    if (lid < LG_RADIX && tile < tiles) {{ lg_hist[lid * tiles + tile] = atomicLoad(&lg_bins[lid]); }}
}}
"
    )
}

/// Workgroup memory and the workgroup scans of the scatter: counts of the 16 digits packed
/// two to a word (16 bits each), four words to a vector.
const SCATTER_SHARED: &str = "
struct LgCounts { lo: vec4<u32>, hi: vec4<u32> }
// The tile, one padding word per 32.
var<workgroup> lg_keys: array<u32, LG_PADDED>;
var<workgroup> lg_values: array<u32, LG_PADDED>;
var<workgroup> lg_lo: array<vec4<u32>, LG_WG>;
var<workgroup> lg_hi: array<vec4<u32>, LG_WG>;
// The tile's counts of each digit.
var<workgroup> lg_total: LgCounts;
// Each digit's first place in the tile.
var<workgroup> lg_start: array<u32, LG_RADIX>;
// Each digit's first place for this tile in the sorted order, less its first place in the
// tile (wrapping).
var<workgroup> lg_delta: array<u32, LG_RADIX>;
var<workgroup> lg_full: u32;
fn lg_pad(i: u32) -> u32 { return i + (i >> 5u); }

// Digit d's count (vectors index in registers; arrays might not).
fn lg_field(c: LgCounts, d: u32) -> u32 {
    let w = select(c.hi, c.lo, d < 8u)[(d >> 1u) & 3u];
    return (w >> ((d & 1u) * 16u)) & 0xffffu;
}

// One more of digit d.
fn lg_bump(c: ptr<function, LgCounts>, d: u32) {
    let one = select(vec4<u32>(0u), vec4<u32>(1u << ((d & 1u) * 16u)), vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>((d >> 1u) & 3u));
    if (d < 8u) { (*c).lo += one; } else { (*c).hi += one; }
}

// The counts of the threads before `rank`, in workgroup memory; the totals into lg_total.
fn lg_tree_exclusive(c: LgCounts, rank: u32) -> LgCounts {
    lg_lo[rank] = c.lo;
    lg_hi[rank] = c.hi;
    workgroupBarrier();
    for (var off = 1u; off < LG_WG; off <<= 1u) {
        var a = vec4<u32>();
        var b = vec4<u32>();
        if (rank >= off) {
            a = lg_lo[rank - off];
            b = lg_hi[rank - off];
        }
        workgroupBarrier();
        lg_lo[rank] += a;
        lg_hi[rank] += b;
        workgroupBarrier();
    }
    if (rank == LG_WG - 1u) { lg_total = LgCounts(lg_lo[rank], lg_hi[rank]); }
    return LgCounts(lg_lo[rank] - c.lo, lg_hi[rank] - c.hi);
}
";

/// The same with subgroup operations, for workgroups of full subgroups.
const SCATTER_SUBGROUP: &str = "
fn lg_sg_exclusive(c: LgCounts, rank: u32, sg: u32, count: u32, size: u32, lane: u32) -> LgCounts {
    let x = LgCounts(subgroupExclusiveAdd(c.lo), subgroupExclusiveAdd(c.hi));
    if (lane == size - 1u) {
        lg_lo[sg] = x.lo + c.lo;
        lg_hi[sg] = x.hi + c.hi;
    }
    workgroupBarrier();
    if (rank == 0u) {
        var lo = vec4<u32>();
        var hi = vec4<u32>();
        for (var s = 0u; s < count; s += 1u) {
            let a = lg_lo[s];
            let b = lg_hi[s];
            lg_lo[s] = lo;
            lg_hi[s] = hi;
            lo += a;
            hi += b;
        }
        lg_total = LgCounts(lo, hi);
    }
    workgroupBarrier();
    return LgCounts(lg_lo[sg] + x.lo, lg_hi[sg] + x.hi);
}
";

/// Each tile's elements ranked by digit and written to their places.
fn scatter_entry(name: &str, subgroups: bool) -> String {
    let (args, rank, exclusive) = if subgroups {
        (
            ", @builtin(subgroup_id) sg: u32, @builtin(num_subgroups) sg_count: u32, @builtin(subgroup_size) sg_size: u32, @builtin(subgroup_invocation_id) lane: u32",
            "    if (lid == 0u) { lg_full = select(0u, 1u, sg_count * sg_size == LG_WG); }
    let full = workgroupUniformLoad(&lg_full) != 0u;
    let rank = select(lid, sg * sg_size + lane, full);
",
            "    var x: LgCounts;
    if (full) { x = lg_sg_exclusive(own, rank, sg, sg_count, sg_size, lane); } else { x = lg_tree_exclusive(own, rank); }
",
        )
    } else {
        (
            "",
            "    let rank = lid;\n",
            "    let x = lg_tree_exclusive(own, rank);\n",
        )
    };
    let shared = if subgroups {
        format!("{SCATTER_SHARED}{SCATTER_SUBGROUP}")
    } else {
        SCATTER_SHARED.to_string()
    };
    format!(
        "{shared}
@compute @workgroup_size({WORKGROUP})
fn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32{args}) {{
    let tile = wid.y * nwg.x + wid.x;
    let n = lg_n();
    let tiles = (n + LG_TILE - 1u) / LG_TILE;
    let base = tile * LG_TILE;
    var m = 0u;
    if (base < n) {{ m = min(n - base, LG_TILE); }}
{rank}{SCATTER_READ}{count}{exclusive}{SCATTER_START}{place}{SCATTER_WRITE}}}
",
        count = run_lines(RUN_COUNT),
        place = run_lines(RUN_PLACE),
    )
}

/// `line` once for each element of a thread's run, `{k}` replaced by its number: straight-line
/// code, so that the run stays in registers.
fn run_lines(line: &str) -> String {
    (0..SORT_ITEMS).map(|k| line.replace("{k}", &k.to_string())).collect()
}

/// The scatter's tile, read in order into workgroup memory.
const SCATTER_READ: &str = "    if (lid < LG_RADIX && tile < tiles) { lg_delta[lid] = lg_hist[lid * tiles + tile]; }
    // The places beyond the elements hold the largest digit, last.
    for (var j = 0u; j < LG_ITEMS; j += 1u) {
        let q = j * LG_WG + lid;
        var key = 0xffffffffu;
        var value = 0u;
        if (q < m) {
            key = lg_src_keys[base + q];
            value = lg_src_values[base + q];
        }
        lg_keys[lg_pad(q)] = key;
        lg_values[lg_pad(q)] = value;
    }
    workgroupBarrier();
    // This thread's run of LG_ITEMS elements, its digits counted: before_k counts the run's
    // elements before k with the same digit.
    var own = LgCounts(vec4<u32>(), vec4<u32>());
";

/// Element k of the run, counted.
const RUN_COUNT: &str = "    let key{k} = lg_keys[lg_pad(rank * LG_ITEMS + {k}u)];
    let value{k} = lg_values[lg_pad(rank * LG_ITEMS + {k}u)];
    let digit{k} = lg_digit(key{k});
    let before{k} = lg_field(own, digit{k});
    lg_bump(&own, digit{k});
";

/// Each digit's first place in the tile, after the workgroup scan of the counts (`x`).
const SCATTER_START: &str = "    workgroupBarrier();
    if (lid < LG_RADIX) {
        var start = 0u;
        for (var e = 0u; e < lid; e += 1u) { start += lg_field(lg_total, e); }
        lg_start[lid] = start;
        lg_delta[lid] -= start;
    }
    workgroupBarrier();
    // Each element to its digit's first place in the tile plus the elements of the digit
    // before it: those of earlier runs, then those of this run.
";

/// Element k of the run to its place in the tile.
const RUN_PLACE: &str = "    let at{k} = lg_pad(lg_start[digit{k}] + lg_field(x, digit{k}) + before{k});
    lg_keys[at{k}] = key{k};
    lg_values[at{k}] = value{k};
";

/// The tile in digit order, each element to its place in the sorted order.
const SCATTER_WRITE: &str = "    workgroupBarrier();
    let room = min(arrayLength(&lg_dst_keys), arrayLength(&lg_dst_values));
    for (var j = 0u; j < LG_ITEMS; j += 1u) {
        let q = j * LG_WG + lid;
        if (q < m) {
            let key = lg_keys[lg_pad(q)];
            let to = lg_delta[lg_digit(key)] + q;
            if (to < room) {
                lg_dst_keys[to] = key;
                lg_dst_values[to] = lg_values[lg_pad(q)];
            }
        }
    }
";
