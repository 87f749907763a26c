//! The scatter of a sort pass ranked by subgroup ballots: 8-bit digits. Each subgroup ranks a
//! contiguous run of the tile, `LG_ITEMS` elements a lane, one element a lane at a time: the
//! ballots of the digit's bits give the lanes holding the same digit, the lanes below among
//! them give the element's rank among its peers, and the lowest of them adds the peers to the
//! subgroup's row of digit counts in workgroup memory (two 16-bit counts a word), whose value
//! before says how many of the digit the subgroup ranked before. An exclusive scan of the rows
//! over the subgroups, and of the tile's counts over the digits, give each element its place in
//! the tile; the tile is reordered in workgroup memory (keys, then values through the same
//! array) and written to its places. The ranking needs every subgroup of the workgroup full:
//! a workgroup that finds otherwise counts its elements into the operator's control word,
//! which the frame reports as an error.

use crate::limits::WORKGROUP;
use std::fmt::Write;

/// Workgroup memory and helpers of the scatter.
const SHARED: &str = "
// Each subgroup's counts of the digits it ranked so far, two 16-bit counts a word; after the
// ranking, each subgroup's first place among the tile's elements of each digit.
var<workgroup> lg_rows: array<atomic<u32>, LG_ROWS * LG_RADIX / 2u>;
// The tile in digit order: its keys, then its values.
var<workgroup> lg_tile: array<u32, LG_TILE>;
// The tile's count of each digit, two a word.
var<workgroup> lg_totals: array<u32, LG_RADIX / 2u>;
// Each digit's first place in the tile.
var<workgroup> lg_start: array<u32, LG_RADIX>;
// Each digit's first place for this tile in the sorted order, less its first place in the
// tile (wrapping).
var<workgroup> lg_delta: array<u32, LG_RADIX>;
// Each subgroup's sum of the tile's counts, then their exclusive scan.
var<workgroup> lg_sums: array<u32, LG_ROWS>;
var<workgroup> lg_full: u32;

// The lanes of a subgroup below `lane`, as a ballot.
fn lg_below(lane: u32) -> vec4<u32> {
    let l = vec4<u32>(lane);
    let first = vec4<u32>(0u, 32u, 64u, 96u);
    let part = (vec4<u32>(1u) << (l - first)) - vec4<u32>(1u);
    return select(select(vec4<u32>(0u), part, l > first), vec4<u32>(0xffffffffu), l >= first + vec4<u32>(32u));
}

// The lanes of a ballot.
fn lg_ones(v: vec4<u32>) -> u32 {
    let c = countOneBits(v);
    return c.x + c.y + c.z + c.w;
}

// The lowest lane of a ballot that is not empty.
fn lg_lowest(v: vec4<u32>) -> u32 {
    let f = firstTrailingBit(v) + vec4<u32>(0u, 32u, 64u, 96u);
    return select(select(select(f.w, f.z, v.z != 0u), f.y, v.y != 0u), f.x, v.x != 0u);
}

// Count of digit d in a word of two 16-bit counts.
fn lg_half(word: u32, d: u32) -> u32 {
    return (word >> ((d & 1u) * 16u)) & 0xffffu;
}

// The rank of this lane's element of digit d among the elements of digit d that subgroup
// `row` ranked before it (this call's lanes below it, then earlier calls'), counting this
// call's elements into the row.
fn lg_rank(d: u32, row: u32, below: vec4<u32>) -> u32 {
    var peers = subgroupBallot(true);
    for (var b = 0u; b < LG_BITS; b += 1u) {
        let one = ((d >> b) & 1u) != 0u;
        let ballot = subgroupBallot(one);
        peers &= select(~ballot, ballot, one);
    }
    let ahead = lg_ones(peers & below);
    var before = 0u;
    if (ahead == 0u) {
        let shift = (d & 1u) * 16u;
        before = lg_half(atomicAdd(&lg_rows[row * (LG_RADIX / 2u) + (d >> 1u)], lg_ones(peers) << shift), d);
    }
    return subgroupShuffle(before, lg_lowest(peers)) + ahead;
}

// Subgroup `row`'s first place among the tile's elements of digit d.
fn lg_row_start(row: u32, d: u32) -> u32 {
    return lg_half(atomicLoad(&lg_rows[row * (LG_RADIX / 2u) + (d >> 1u)]), d);
}
";

/// The entry's start: the tile, its elements, the rows cleared and the tile's places in the
/// sorted order read; whether the subgroups are full.
const START: &str = "    let tile = wid.y * nwg.x + wid.x;
    let n = lg_n();
    let tiles = (n + LG_TILE - 1u) / LG_TILE;
    let base = tile * LG_TILE;
    var m = 0u;
    if (base < n) { m = min(n - base, LG_TILE); }
    for (var w = lid; w < LG_ROWS * LG_RADIX / 2u; w += LG_WG) { atomicStore(&lg_rows[w], 0u); }
    if (tile < tiles) { lg_delta[lid] = lg_hist[lid * tiles + tile]; }
    if (lid == 0u) { lg_full = select(0u, 1u, sg_count * sg_size == LG_WG && sg_count <= LG_ROWS); }
    let full = workgroupUniformLoad(&lg_full) != 0u;
    if (!full) {
        if (lid == 0u) { atomicAdd(&lg_control[LG_OVERFLOW], m); }
        return;
    }
    // This subgroup's run of the tile, and this lane's digit in the scans over digits.
    let chunk = sg * sg_size * LG_ITEMS;
    let me = sg * sg_size + lane;
    let below = lg_below(lane);
    // The places beyond the elements hold the largest digit, last.
";

/// Element k of the lane, read and ranked.
const RANK: &str = "    let q{k} = chunk + {k}u * sg_size + lane;
    var key{k} = 0xffffffffu;
    if (q{k} < m) { key{k} = lg_src_keys[base + q{k}]; }
    let digit{k} = lg_digit(key{k});
    let rank{k} = lg_rank(digit{k}, sg, below);
";

/// The value of element k, read.
const READ_VALUE: &str = "    var value{k} = 0u;
    if (q{k} < m) { value{k} = lg_value(base + q{k}); }
";

/// The scans: each subgroup's first place among each digit's elements, each digit's first
/// place in the tile.
const SCANS: &str = "    workgroupBarrier();
    if (lid < LG_RADIX / 2u) {
        var run = 0u;
        for (var r = 0u; r < sg_count; r += 1u) {
            let c = atomicLoad(&lg_rows[r * (LG_RADIX / 2u) + lid]);
            atomicStore(&lg_rows[r * (LG_RADIX / 2u) + lid], run);
            run += c;
        }
        lg_totals[lid] = run;
    }
    workgroupBarrier();
    let count = lg_half(lg_totals[me >> 1u], me);
    let x = subgroupExclusiveAdd(count);
    if (lane == sg_size - 1u) { lg_sums[sg] = x + count; }
    workgroupBarrier();
    if (lid == 0u) {
        var run = 0u;
        for (var s = 0u; s < sg_count; s += 1u) {
            let c = lg_sums[s];
            lg_sums[s] = run;
            run += c;
        }
    }
    workgroupBarrier();
    let start = lg_sums[sg] + x;
    lg_start[me] = start;
    lg_delta[me] -= start;
    workgroupBarrier();
";

/// Element k to its place in the tile.
const PLACE: &str = "    let at{k} = lg_start[digit{k}] + lg_row_start(sg, digit{k}) + rank{k};
    lg_tile[at{k}] = key{k};
";

/// Element j of the tile in digit order to its place in the sorted order.
const WRITE_KEY: &str = "    let q{k}w = {k}u * LG_WG + lid;
    var to{k} = 0xffffffffu;
    if (q{k}w < m) {
        let key = lg_tile[q{k}w];
        to{k} = lg_delta[lg_digit(key)] + q{k}w;
        if (to{k} < room) { lg_dst_keys[to{k}] = key; }
    }
";

/// Value k to its place in the tile.
const PLACE_VALUE: &str = "    lg_tile[at{k}] = value{k};
";

/// Value j of the tile in digit order to its place in the sorted order.
const WRITE_VALUE: &str = "    if (q{k}w < m && to{k} < room) { lg_put_value(to{k}, lg_tile[q{k}w]); }
";

/// `text` once for each element of a lane, `{k}` replaced by its number: straight-line code,
/// so that the elements stay in registers.
fn each(items: u32, text: &str) -> String {
    (0..items).map(|k| text.replace("{k}", &k.to_string())).collect()
}

/// Each tile's elements (with their values where `values`, `items` a thread) ranked by digit
/// and written to their places; partial subgroups counted into control word `overflow`.
pub(super) fn scatter_entry(name: &str, items: u32, values: bool, overflow: u32) -> String {
    let mut body = String::new();
    body.push_str(START);
    body.push_str(&each(items, RANK));
    if values {
        body.push_str(&each(items, READ_VALUE));
    }
    body.push_str(SCANS);
    body.push_str(&each(items, PLACE));
    body.push_str("    workgroupBarrier();\n    let room = lg_room();\n");
    body.push_str(&each(items, WRITE_KEY));
    if values {
        body.push_str("    workgroupBarrier();\n");
        body.push_str(&each(items, PLACE_VALUE));
        body.push_str("    workgroupBarrier();\n");
        body.push_str(&each(items, WRITE_VALUE));
    }
    let mut out = format!("const LG_OVERFLOW: u32 = {overflow}u;\n{SHARED}");
    let _ = write!(
        out,
        "@compute @workgroup_size({WORKGROUP})
fn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(subgroup_id) sg: u32, @builtin(num_subgroups) sg_count: u32, @builtin(subgroup_size) sg_size: u32, @builtin(subgroup_invocation_id) lane: u32) {{
{body}}}
"
    );
    out
}
