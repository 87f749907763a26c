//! The operator kernels' scaffolding and the exclusive scan they share: a module with the
//! frame record and its buffers, the workgroups of a dispatch, and the scan of `u32` or `f32`
//! elements (reduce-then-scan: tile sums, a scan of the sums, tiles rescanned with their
//! offsets, as many levels as the length needs), which the `Scan` operator runs and the radix
//! sort ([`crate::radix`]) runs over its digit histograms. Reduce-then-scan needs no
//! forward-progress guarantee between workgroups, so it runs on any adapter. Where the adapter
//! has subgroups the tile scans use subgroup operations, of whatever size the adapter runs,
//! when every subgroup of the workgroup is full (checked in the kernel); otherwise, and without
//! subgroups, a scan in workgroup memory.

use crate::ids::{OpId, ResourceId};
use crate::limits::{FRAME_BINDING, WORKGROUP};
use crate::resolve::BufferRef;
use std::fmt::Write;

/// How many workgroups a dispatch of an operator kernel needs for `n` elements of the
/// operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Groups {
    /// Elements per workgroup at the kernel's level (a scan's tile).
    pub per_group: u64,
    /// Scan level (0: the elements themselves); each level holds one sum per group of the
    /// level below.
    pub level: usize,
    /// `Some((tile, words))` when level 0 is not the elements but `words` words per tile of
    /// `tile` elements (a sort's digit histograms; a gather's words, one thread each).
    pub per_tile: Option<(u64, u64)>,
}

impl Groups {
    /// One workgroup per `per_group` elements of the operator.
    pub fn elements(per_group: u64) -> Groups {
        Groups {
            per_group,
            level: 0,
            per_tile: None,
        }
    }

    /// Workgroups for `n` elements of the operator.
    pub fn count(&self, n: u64) -> u64 {
        let mut n = match self.per_tile {
            Some((tile, words)) => n.div_ceil(tile) * words,
            None => n,
        };
        for _ in 0..self.level {
            n = n.div_ceil(self.per_group);
        }
        n.div_ceil(self.per_group).max(1)
    }
}

/// One kernel of an operator.
#[derive(Debug, Clone)]
pub struct OpKernel {
    /// Entry point name.
    pub name: String,
    /// The WGSL module.
    pub wgsl: String,
    /// Buffers by binding number in group 0 (the frame record is group 1).
    pub bindings: Vec<(u32, BufferRef)>,
    /// Its workgroups.
    pub groups: Groups,
}

/// A module being written: a header with the frame record and control words, then the
/// operator's buffers.
pub(crate) struct Module {
    /// The WGSL so far.
    pub text: String,
    bindings: Vec<(u32, BufferRef)>,
}

impl Module {
    /// A module with the frame record, and the control words with `control`.
    pub fn new(control: bool) -> Module {
        let mut m = Module {
            text: format!(
                "struct Frame {{ index: u32, seed: u32, base: u32, count: u32 }}\n{}",
                FRAME_BINDING
            ),
            bindings: Vec::new(),
        };
        if control {
            m.bind("lg_control", "array<atomic<u32>>", BufferRef::Control);
        }
        m
    }

    /// Declares `buffer` as `var<storage, read_write> name: ty` at the next binding.
    pub fn bind(&mut self, name: &str, ty: &str, buffer: BufferRef) {
        let n = self.bindings.len() as u32;
        let _ = writeln!(
            self.text,
            "@group(0) @binding({n}) var<storage, read_write> {name}: {ty};"
        );
        self.bindings.push((n, buffer));
    }

    /// `fn lg_n() -> u32`: the operator's elements, from the record or its GPU counter.
    pub fn element_count(&mut self, counted: Option<ResourceId>) {
        match counted {
            Some(c) => {
                self.bind("lg_counter", "array<u32>", BufferRef::Resource(c));
                self.text
                    .push_str("fn lg_n() -> u32 { return min(lg_counter[0], frame.count); }\n");
            }
            None => self.text.push_str("fn lg_n() -> u32 { return frame.count; }\n"),
        }
    }

    /// The kernel with entry point `name`.
    pub fn finish(self, name: String, groups: Groups) -> OpKernel {
        OpKernel {
            name,
            wgsl: self.text,
            bindings: self.bindings,
            groups,
        }
    }
}

/// The entry point header of an element-wise kernel: `i`, the element of the thread.
pub(crate) fn element_entry(name: &str) -> String {
    format!(
        "@compute @workgroup_size({WORKGROUP})\nfn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {{\n    let i = (wid.y * nwg.x + wid.x) * {WORKGROUP}u + lid;\n"
    )
}

/// A scan to generate.
pub(crate) struct Scan {
    /// The operator it belongs to (whose scratch holds the partial sums).
    pub o: OpId,
    /// The WGSL type of the elements and their sums: `u32` (wrapping) or `f32`.
    pub element: &'static str,
    /// The elements summed (level 0).
    pub input: BufferRef,
    /// Where their sums go (may be `input`).
    pub output: BufferRef,
    /// The operator's scratch buffer of the first level of partial sums; the others follow.
    pub partials: usize,
    /// Levels of partial sums.
    pub levels: usize,
    /// Level 0's elements, a WGSL expression of `lg_n()` (the operator's elements).
    pub length: String,
    /// As [`Groups::per_tile`], for level 0.
    pub per_tile: Option<(u64, u64)>,
    /// The resource counting the operator's elements on the GPU.
    pub counted: Option<ResourceId>,
    /// Whether to use subgroup operations.
    pub subgroups: bool,
    /// Elements per thread.
    pub items: u32,
}

impl Scan {
    fn tile(&self) -> u64 {
        (WORKGROUP * self.items) as u64
    }

    /// Level l's elements: the input at level 0, partial sums above.
    fn level_buffer(&self, l: usize) -> BufferRef {
        if l == 0 {
            self.input.clone()
        } else {
            BufferRef::Scratch(self.o, self.partials + l - 1)
        }
    }

    fn groups(&self, level: usize) -> Groups {
        Groups {
            per_group: self.tile(),
            level,
            per_tile: self.per_tile,
        }
    }

    /// The kernels: per level below the top, the tile sums; then per level, top down, the
    /// tiles rescanned with their offsets. The top level (one tile at most) is not scanned
    /// apart: the level below sums the top's values before each of its tiles itself (or, for
    /// a single tile, starts at 0).
    pub fn kernels(&self, prefix: &str) -> Vec<OpKernel> {
        let levels = self.levels;
        let mut out = Vec::new();
        for l in 0..levels {
            let mut m = self.module(l);
            m.bind("lg_src", "array<LgElement>", self.level_buffer(l));
            m.bind(
                "lg_dst",
                "array<LgElement>",
                BufferRef::Scratch(self.o, self.partials + l),
            );
            let name = format!("{prefix}_reduce{l}");
            m.text.push_str(&scan_reduce_entry(&name, self.subgroups));
            out.push(m.finish(name, self.groups(l)));
        }
        for l in (0..levels.max(1)).rev() {
            let mut m = self.module(l);
            let dst = if l == 0 {
                self.output.clone()
            } else {
                self.level_buffer(l)
            };
            let in_place = dst == self.level_buffer(l);
            m.bind("lg_src", "array<LgElement>", self.level_buffer(l));
            if !in_place {
                m.bind("lg_dst", "array<LgElement>", dst);
            }
            let offsets = match l + 1 {
                top if top == levels => Offsets::Sums,
                above if above < levels => Offsets::Scanned,
                _ => Offsets::Zero,
            };
            if offsets != Offsets::Zero {
                m.bind(
                    "lg_offsets",
                    "array<LgElement>",
                    BufferRef::Scratch(self.o, self.partials + l),
                );
            }
            let name = format!("{prefix}_down{l}");
            m.text
                .push_str(&scan_down_entry(&name, in_place, offsets, self.subgroups));
            out.push(m.finish(name, self.groups(l)));
        }
        out
    }

    /// A scan module's shared part: the element type (`LgElement`), sizes, workgroup memory,
    /// the level's element count and the workgroup-wide sums.
    fn module(&self, level: usize) -> Module {
        let mut m = Module::new(false);
        m.element_count(self.counted);
        let tile = self.tile();
        let _ = write!(
            m.text,
            "alias LgElement = {};\nconst LG_WG: u32 = {WORKGROUP}u;\nconst LG_ITEMS: u32 = {}u;\nconst LG_TILE: u32 = {tile}u;\n\
             // The tile in workgroup memory, one padding word per 32 so that threads reading their\n\
             // own consecutive elements hit distinct banks.\n\
             var<workgroup> lg_tile: array<LgElement, {}>;\n\
             // Elements at this level: each level above holds one sum per tile of the one below.\n\
             fn lg_level_n() -> u32 {{\n    var n = {};\n    for (var l = 0u; l < {level}u; l += 1u) {{ n = (n + LG_TILE - 1u) / LG_TILE; }}\n    return n;\n}}\n",
            self.element,
            self.items,
            tile + tile / 32 + 1,
            self.length
        );
        m.text.push_str(SCAN_SHARED);
        if self.subgroups {
            m.text.push_str(SCAN_SUBGROUP);
        }
        m
    }
}

/// Workgroup memory and the subgroup-free workgroup sums of the scan kernels, of `LgElement`s.
/// Barriers stand only in control flow uniform over the workgroup (naga checks it). Every sum
/// adds in an order fixed by the kernel, the same for every thread and every run, so that `f32`
/// sums are reproducible and every thread of a workgroup holds the same one.
const SCAN_SHARED: &str = "
var<workgroup> lg_sums: array<LgElement, 256>;
var<workgroup> lg_full: u32;
fn lg_pad(i: u32) -> u32 { return i + (i >> 5u); }

// Sum of `v` over the workgroup, in workgroup memory.
fn lg_tree_sum(v: LgElement, lid: u32) -> LgElement {
    lg_sums[lid] = v;
    for (var off = LG_WG / 2u; off > 0u; off >>= 1u) {
        workgroupBarrier();
        if (lid < off) { lg_sums[lid] += lg_sums[lid + off]; }
    }
    workgroupBarrier();
    return lg_sums[0];
}

// Sum of the values before `v` (in the order of `rank`) over the workgroup, in workgroup
// memory: the inclusive sum of the thread before (an f32 inclusive sum minus `v` would lose
// what stands before a large `v` to rounding).
fn lg_tree_exclusive(v: LgElement, rank: u32) -> LgElement {
    lg_sums[rank] = v;
    workgroupBarrier();
    for (var off = 1u; off < LG_WG; off <<= 1u) {
        var before = LgElement(0);
        if (rank >= off) { before = lg_sums[rank - off]; }
        workgroupBarrier();
        lg_sums[rank] += before;
        workgroupBarrier();
    }
    if (rank == 0u) { return LgElement(0); }
    return lg_sums[rank - 1u];
}
";

/// Workgroup sums with subgroup operations, for workgroups of full subgroups (`rank` is then
/// `subgroup * size + lane`, which numbers the threads 0 .. LG_WG in subgroup order).
const SCAN_SUBGROUP: &str = "
// Sum of `v` over the workgroup: the sums of the `count` subgroups, added in subgroup order by
// every thread (no atomic: WGSL has no f32 atomics, and their order would vary).
fn lg_sg_sum(v: LgElement, sg: u32, count: u32, lane: u32) -> LgElement {
    let s = subgroupAdd(v);
    if (lane == 0u) { lg_sums[sg] = s; }
    workgroupBarrier();
    var total = LgElement(0);
    for (var k = 0u; k < count; k += 1u) { total += lg_sums[k]; }
    return total;
}

// Sum of the values before `v` in the order of `rank`.
fn lg_sg_exclusive(v: LgElement, rank: u32, sg: u32, count: u32, size: u32, lane: u32) -> LgElement {
    let x = subgroupExclusiveAdd(v);
    if (lane == size - 1u) { lg_sums[sg] = x + v; }
    workgroupBarrier();
    if (rank == 0u) {
        var run = LgElement(0);
        for (var s = 0u; s < count; s += 1u) {
            let t = lg_sums[s];
            lg_sums[s] = run;
            run += t;
        }
    }
    workgroupBarrier();
    return lg_sums[sg] + x;
}
";

/// The entry point's start: the tile, the level's elements, and the thread's rank (in
/// subgroup order where every subgroup is full, decided uniformly for the workgroup).
fn scan_entry_head(name: &str, subgroups: bool) -> String {
    let (args, rank) = if subgroups {
        (
            ", @builtin(subgroup_id) sg: u32, @builtin(num_subgroups) sg_count: u32, @builtin(subgroup_size) sg_size: u32, @builtin(subgroup_invocation_id) lane: u32",
            "    if (lid == 0u) {
        lg_full = select(0u, 1u, sg_count * sg_size == LG_WG);
    }
    let full = workgroupUniformLoad(&lg_full) != 0u;
    let rank = select(lid, sg * sg_size + lane, full);
",
        )
    } else {
        ("", "    let rank = lid;\n")
    };
    format!(
        "@compute @workgroup_size({WORKGROUP})\nfn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32{args}) {{\n    let tile = wid.y * nwg.x + wid.x;\n    let n = lg_level_n();\n    let base = tile * LG_TILE;\n{rank}"
    )
}

/// Sums of each tile of the level into the level above.
fn scan_reduce_entry(name: &str, subgroups: bool) -> String {
    let total = if subgroups {
        "    var total: LgElement;\n    if (full) { total = lg_sg_sum(s, sg, sg_count, lane); } else { total = lg_tree_sum(s, lid); }\n"
    } else {
        "    let total = lg_tree_sum(s, lid);\n"
    };
    format!(
        "{}    var s = LgElement(0);
    if (base + LG_TILE <= n) {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{ s += lg_src[base + j * LG_WG + lid]; }}
    }} else {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{
            let i = base + j * LG_WG + lid;
            if (i < n) {{ s += lg_src[i]; }}
        }}
    }}
{total}    if (lid == 0u && tile < arrayLength(&lg_dst)) {{ lg_dst[tile] = total; }}
}}
",
        scan_entry_head(name, subgroups)
    )
}

/// Where a tile's offset comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Offsets {
    /// The only tile: 0.
    Zero,
    /// The sums of the tiles before it, from the top level's unscanned values.
    Sums,
    /// The level above, scanned.
    Scanned,
}

/// Each tile's exclusive scan plus its offset from the level above.
fn scan_down_entry(name: &str, in_place: bool, offsets: Offsets, subgroups: bool) -> String {
    let dst = if in_place { "lg_src" } else { "lg_dst" };
    let sum = if subgroups {
        "    if (full) { offset = lg_sg_sum(before, sg, sg_count, lane); } else { offset = lg_tree_sum(before, lid); }\n"
    } else {
        "    offset = lg_tree_sum(before, lid);\n"
    };
    let offset = match offsets {
        Offsets::Zero => "    let offset = LgElement(0);\n".to_string(),
        Offsets::Scanned => {
            "    var offset = LgElement(0);\n    if (base < n) { offset = lg_offsets[tile]; }\n".to_string()
        }
        Offsets::Sums => format!(
            "    // The sum of the tiles before this one.\n    var before = LgElement(0);\n    for (var j = lid; j < tile; j += LG_WG) {{ before += lg_offsets[j]; }}\n    var offset: LgElement;\n{sum}    workgroupBarrier();\n"
        ),
    };
    let exclusive = if subgroups {
        "    var run: LgElement;\n    if (full) { run = lg_sg_exclusive(t, rank, sg, sg_count, sg_size, lane); } else { run = lg_tree_exclusive(t, rank); }\n"
    } else {
        "    var run = lg_tree_exclusive(t, rank);\n"
    };
    format!(
        "{head}{offset}    let whole = base + LG_TILE <= n;
    if (whole) {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{ lg_tile[lg_pad(j * LG_WG + lid)] = lg_src[base + j * LG_WG + lid]; }}
    }} else {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{
            let i = base + j * LG_WG + lid;
            var v = LgElement(0);
            if (i < n) {{ v = lg_src[i]; }}
            lg_tile[lg_pad(j * LG_WG + lid)] = v;
        }}
    }}
    workgroupBarrier();
    let first = rank * LG_ITEMS;
    var t = LgElement(0);
    for (var k = 0u; k < LG_ITEMS; k += 1u) {{ t += lg_tile[lg_pad(first + k)]; }}
{exclusive}    run += offset;
    for (var k = 0u; k < LG_ITEMS; k += 1u) {{
        let at = lg_pad(first + k);
        let v = lg_tile[at];
        lg_tile[at] = run;
        run += v;
    }}
    workgroupBarrier();
    if (whole) {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{ {dst}[base + j * LG_WG + lid] = lg_tile[lg_pad(j * LG_WG + lid)]; }}
    }} else {{
        for (var j = 0u; j < LG_ITEMS; j += 1u) {{
            let i = base + j * LG_WG + lid;
            if (i < n) {{ {dst}[i] = lg_tile[lg_pad(j * LG_WG + lid)]; }}
        }}
    }}
}}
",
        head = scan_entry_head(name, subgroups)
    )
}
