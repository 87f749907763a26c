//! The portable scatter of a sort pass: 4-bit digits ranked by per-thread counts. Each thread
//! counts the 16 digits of its run of elements (packed two to a word, in registers), a
//! workgroup scan of the counts (subgroup operations where every subgroup is full, workgroup
//! memory otherwise) gives each element its place in the tile, the tile is reordered in
//! workgroup memory and written to its places.

use crate::limits::WORKGROUP;
use crate::scratch::SORT_ITEMS;

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
pub(super) fn scatter_entry(name: &str, subgroups: bool) -> String {
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
            value = lg_value(base + q);
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
    let room = lg_room();
    for (var j = 0u; j < LG_ITEMS; j += 1u) {
        let q = j * LG_WG + lid;
        if (q < m) {
            let key = lg_keys[lg_pad(q)];
            let to = lg_delta[lg_digit(key)] + q;
            if (to < room) {
                lg_dst_keys[to] = key;
                lg_put_value(to, lg_values[lg_pad(q)]);
            }
        }
    }
";
