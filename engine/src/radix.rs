//! The kernels of the `Sort` operator: a stable LSD radix sort of `u32` keys, optionally
//! carrying `u32` values. Each pass counts the digits of every tile into histograms stored
//! digit-major (digit `d` of tile `t` at `d * tiles + t`), so that one exclusive scan of them
//! (the scan operator's kernels) gives each tile the first place of each of its digits in the
//! sorted order; then each tile ranks its elements by digit (ties in element order),
//! reorders them in workgroup memory and writes them to their places. Two rankings, chosen
//! by the target's [`SortShape`]: 8-bit digits ranked by subgroup ballots ([`ballots`], four
//! passes for 32 bits), or 4-bit digits ranked by per-thread counts on any adapter
//! ([`counts`], eight passes). Keys and values go back and forth between the operator's
//! buffers and two scratch buffers, copied back at the end when the passes are odd. No kernel
//! waits on another workgroup, so the sort needs no forward-progress guarantee.

mod ballots;
mod counts;

use crate::ids::{OpId, ResourceId};
use crate::limits::WORKGROUP;
use crate::resolve::{BufferRef, Resolved};
use crate::scan::{Groups, Module, OpKernel, Scan, element_entry};
use crate::scratch::{HISTOGRAMS, KEYS, PARTIALS, SortShape, VALUES};
use std::fmt::Write;

/// A sort to generate.
pub(crate) struct Sort {
    /// The operator.
    pub o: OpId,
    /// Its keys.
    pub keys: ResourceId,
    /// Its values, if any.
    pub values: Option<ResourceId>,
    /// Low bits sorted by.
    pub bits: u32,
    /// The resource counting its elements on the GPU.
    pub counted: Option<ResourceId>,
    /// Whether to use subgroup operations.
    pub subgroups: bool,
    /// Elements per thread of the histogram scans.
    pub items: u32,
    /// How its passes rank.
    pub shape: SortShape,
    /// Its control word counting elements it could not rank (a ballot-ranked pass on a
    /// workgroup whose subgroups are not all full).
    pub overflow: u32,
}

/// One side of the ping-pong: keys, and values when the sort has them.
type Side = (BufferRef, Option<BufferRef>);

impl Sort {
    /// The kernels: per pass, the digit histograms, their scan and the scatter; then the copy
    /// back when the last pass wrote the scratch.
    pub fn kernels(&self, prefix: &str, resolved: &Resolved) -> Vec<OpKernel> {
        let levels = resolved.op_scratch[&self.o].len() - PARTIALS;
        let operand: Side = (BufferRef::Resource(self.keys), self.values.map(BufferRef::Resource));
        let scratch: Side = (
            BufferRef::Scratch(self.o, KEYS),
            self.values.map(|_| BufferRef::Scratch(self.o, VALUES)),
        );
        let tiles = Groups::elements(self.shape.tile());
        let passes = self.shape.passes(self.bits);
        let mut out = Vec::new();
        for p in 0..passes {
            let (src, dst) = match p % 2 {
                0 => (&operand, &scratch),
                _ => (&scratch, &operand),
            };
            let shift = p * self.shape.digit_bits;
            let width = (self.bits - shift).min(self.shape.digit_bits);
            let mut m = self.module(shift, width, false);
            m.bind("lg_src", "array<u32>", src.0.clone());
            m.bind("lg_hist", "array<u32>", BufferRef::Scratch(self.o, HISTOGRAMS));
            let name = format!("{prefix}_digits{p}");
            m.text.push_str(&digits_entry(&name));
            out.push(m.finish(name, tiles));
            out.extend(self.scan(levels).kernels(&format!("{prefix}_scan{p}")));
            let mut m = self.module(shift, width, self.shape.ballots());
            bind_moved(&mut m, src, dst);
            m.bind("lg_hist", "array<u32>", BufferRef::Scratch(self.o, HISTOGRAMS));
            let name = format!("{prefix}_scatter{p}");
            let entry = if self.shape.ballots() {
                ballots::scatter_entry(&name, self.shape.items, self.values.is_some(), self.overflow)
            } else {
                counts::scatter_entry(&name, self.subgroups)
            };
            m.text.push_str(&entry);
            out.push(m.finish(name, tiles));
        }
        if passes % 2 == 1 {
            out.push(self.copy_back(prefix, &operand, &scratch));
        }
        out
    }

    /// The exclusive scan of the histograms, in place, with `levels` of partial sums.
    fn scan(&self, levels: usize) -> Scan {
        let histograms = BufferRef::Scratch(self.o, HISTOGRAMS);
        let (tile, radix) = (self.shape.tile(), self.shape.radix());
        Scan {
            o: self.o,
            element: "u32",
            input: histograms.clone(),
            output: histograms,
            partials: PARTIALS,
            levels,
            length: format!("{radix}u * ((lg_n() + {tile}u - 1u) / {tile}u)"),
            per_tile: Some((tile, radix)),
            counted: self.counted,
            subgroups: self.subgroups,
            items: self.items,
        }
    }

    /// A pass's module (with the control words where `control`): its digit, of `width` bits
    /// from bit `shift`, and the tile's shape.
    fn module(&self, shift: u32, width: u32, control: bool) -> Module {
        let mut m = Module::new(control);
        m.element_count(self.counted);
        let shape = self.shape;
        let tile = shape.tile();
        let _ = write!(
            m.text,
            "const LG_WG: u32 = {WORKGROUP}u;\nconst LG_ITEMS: u32 = {}u;\nconst LG_TILE: u32 = {tile}u;\nconst LG_RADIX: u32 = {}u;\nconst LG_ROWS: u32 = {}u;\nconst LG_BITS: u32 = {width}u;\nconst LG_PADDED: u32 = {};\n\
             // This pass's digit of a key.\n\
             fn lg_digit(key: u32) -> u32 {{ return (key >> {shift}u) & {}u; }}\n",
            shape.items,
            shape.radix(),
            shape.rows.max(1),
            tile + tile / 32 + 1,
            (1u64 << width) - 1
        );
        m
    }

    /// The copy of the sorted keys and values from the scratch into the operator's buffers.
    fn copy_back(&self, prefix: &str, operand: &Side, scratch: &Side) -> OpKernel {
        let mut m = Module::new(false);
        bind_moved(&mut m, scratch, operand);
        m.element_count(self.counted);
        let name = format!("{prefix}_copy");
        let _ = write!(
            m.text,
            "{}    if (i < lg_n()) {{\n        lg_dst_keys[i] = lg_src_keys[i];\n        lg_put_value(i, lg_value(i));\n    }}\n}}\n",
            element_entry(&name)
        );
        m.finish(name, Groups::elements(WORKGROUP as u64))
    }
}

/// Binds the keys (and values) a kernel moves from `src` to `dst`, with the value accessors
/// the scatters and the copy call: `lg_value(i)`, `lg_put_value(i, v)` (nothing without
/// values) and `lg_room()`, the places the destination holds.
fn bind_moved(m: &mut Module, src: &Side, dst: &Side) {
    m.bind("lg_src_keys", "array<u32>", src.0.clone());
    m.bind("lg_dst_keys", "array<u32>", dst.0.clone());
    match (&src.1, &dst.1) {
        (Some(from), Some(to)) => {
            m.bind("lg_src_values", "array<u32>", from.clone());
            m.bind("lg_dst_values", "array<u32>", to.clone());
            m.text.push_str(
                "fn lg_value(i: u32) -> u32 { return lg_src_values[i]; }\n\
                 fn lg_put_value(i: u32, v: u32) { lg_dst_values[i] = v; }\n\
                 fn lg_room() -> u32 { return min(arrayLength(&lg_dst_keys), arrayLength(&lg_dst_values)); }\n",
            );
        }
        _ => m.text.push_str(
            "fn lg_value(i: u32) -> u32 { return 0u; }\n\
             fn lg_put_value(i: u32, v: u32) {}\n\
             fn lg_room() -> u32 { return arrayLength(&lg_dst_keys); }\n",
        ),
    }
}

/// The digit histogram of each tile, digit-major.
fn digits_entry(name: &str) -> String {
    format!(
        "var<workgroup> lg_bins: array<atomic<u32>, LG_RADIX>;
@compute @workgroup_size({WORKGROUP})
fn {name}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {{
    let tile = wid.y * nwg.x + wid.x;
    let n = lg_n();
    for (var d = lid; d < LG_RADIX; d += LG_WG) {{ atomicStore(&lg_bins[d], 0u); }}
    workgroupBarrier();
    let base = tile * LG_TILE;
    for (var j = 0u; j < LG_ITEMS; j += 1u) {{
        let i = base + j * LG_WG + lid;
        if (i < n) {{ atomicAdd(&lg_bins[lg_digit(lg_src[i])], 1u); }}
    }}
    workgroupBarrier();
    let tiles = (n + LG_TILE - 1u) / LG_TILE;
    if (tile < tiles) {{
        for (var d = lid; d < LG_RADIX; d += LG_WG) {{ lg_hist[d * tiles + tile] = atomicLoad(&lg_bins[d]); }}
    }}
}}
"
    )
}
