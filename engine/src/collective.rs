//! The kernels of the collective operators, written once and generated for each use: fill,
//! exclusive scan (the kernels of [`crate::scan`]), the count and scatter steps of a counting
//! sort, the gather, and the radix sort ([`crate::radix`]).

use crate::graph::Graph;
use crate::ids::{OpId, ResourceId};
use crate::limits::{Target, WORKGROUP};
use crate::operator::{OpKind, summed_type};
use crate::radix::Sort;
use crate::resolve::{BufferRef, Resolved};
use crate::scan::{Groups, Module, OpKernel, Scan, element_entry};
use std::fmt::Write;

/// The kernels of operator `o` of `graph`, in the order they run, for `target`: subgroup
/// operations where it has them, scans in tiles of `WORKGROUP * scan_items` elements, sorts in
/// the shape the resolve stage found for it ([`Resolved::sort_shape`]).
pub fn op_kernels(graph: &Graph, o: OpId, resolved: &Resolved, target: &Target) -> Vec<OpKernel> {
    let (subgroups, items) = (target.subgroups(), target.scan_items);
    let op = &graph.ops[o];
    let counted = op.domain.as_ref().and_then(|d| d.counted);
    let words = |r: &ResourceId| resolved.sizes[*r].element_bytes / 4;
    let resource = |r: &ResourceId| BufferRef::Resource(*r);
    let element = Groups::elements(WORKGROUP as u64);
    let prefix = format!("lg_op{}", o.0);
    match &op.kind {
        OpKind::Clear { buffer, value, .. } => {
            let mut m = Module::new(false);
            m.bind("lg_buffer", "array<u32>", resource(buffer));
            let name = format!("{prefix}_fill");
            // The record's base and count are the first word and the words to fill.
            let _ = write!(
                m.text,
                "{}    if (i < frame.count) {{ lg_buffer[frame.base + i] = {}u; }}\n}}\n",
                element_entry(&name),
                value.bits()
            );
            vec![m.finish(name, element)]
        }
        OpKind::Count { keys, counts, slots } => {
            let mut m = Module::new(true);
            m.bind("lg_keys", "array<u32>", resource(keys));
            m.bind("lg_counts", "array<atomic<u32>>", resource(counts));
            m.bind("lg_slots", "array<u32>", resource(slots));
            m.element_count(counted);
            let name = format!("{prefix}_count");
            let overflow = resolved.control.op_overflow[&o];
            let _ = write!(
                m.text,
                "{}    if (i >= lg_n()) {{ return; }}\n    let k = lg_keys[i];\n    if (k < arrayLength(&lg_counts)) {{\n        lg_slots[i] = atomicAdd(&lg_counts[k], 1u);\n    }} else {{\n        atomicAdd(&lg_control[{overflow}], 1u);\n    }}\n}}\n",
                element_entry(&name)
            );
            vec![m.finish(name, element)]
        }
        OpKind::Scatter {
            keys,
            slots,
            offsets,
            input,
            output,
        } => {
            let sorted = [keys, slots, offsets].map(resource);
            let moved = input.as_ref().map(|i| (resource(i), words(i)));
            let overflow = resolved.control.op_overflow[&o];
            vec![scatter_kernel(
                &prefix,
                sorted,
                moved,
                resource(output),
                counted,
                overflow,
            )]
        }
        OpKind::Gather { indices, input, output } => {
            let buffers = [indices, input, output].map(resource);
            let overflow = resolved.control.op_overflow[&o];
            vec![gather_kernel(&prefix, buffers, counted, words(input), overflow)]
        }
        OpKind::Scan { input, output } => {
            let scan = Scan {
                o,
                element: summed_type(&graph.resources[*input].decl.ty).expect("the load checks a scan's elements"),
                input: resource(input),
                output: resource(output),
                partials: 0,
                levels: resolved.op_scratch[&o].len(),
                length: "lg_n()".to_string(),
                per_tile: None,
                counted,
                subgroups,
                items,
            };
            scan.kernels(&prefix)
        }
        OpKind::Sort { keys, values, bits } => {
            let sort = Sort {
                o,
                keys: *keys,
                values: *values,
                bits: *bits,
                counted,
                subgroups,
                items,
                shape: resolved.sort_shape,
                overflow: resolved.control.op_overflow[&o],
            };
            sort.kernels(&prefix, resolved)
        }
    }
}

/// The scatter of a counting sort over `sorted` (keys, slots, offsets) into `output`: each
/// element to its bucket's first place plus its slot. `moved` is the input and its elements'
/// words, or none to move each element's index. Elements of a multiple of 4 words move as
/// 16-byte vectors (a 48-byte cache vertex in 3 loads and 3 stores instead of 12 of each).
fn scatter_kernel(
    prefix: &str,
    sorted: [BufferRef; 3],
    moved: Option<(BufferRef, u32)>,
    output: BufferRef,
    counted: Option<ResourceId>,
    overflow: u32,
) -> OpKernel {
    let mut m = Module::new(true);
    let [keys, slots, offsets] = sorted;
    let w = moved.as_ref().map_or(1, |(_, w)| *w);
    let (word, w) = moved_words(w);
    m.bind("lg_keys", "array<u32>", keys);
    m.bind("lg_slots", "array<u32>", slots);
    m.bind("lg_offsets", "array<u32>", offsets);
    let mut copy = String::new();
    match moved {
        Some((input, _)) => {
            m.bind("lg_input", &format!("array<{word}>"), input);
            for k in 0..w {
                let _ = writeln!(copy, "    lg_output[d * {w}u + {k}u] = lg_input[i * {w}u + {k}u];");
            }
        }
        None => copy.push_str("    lg_output[d] = i;\n"),
    }
    m.bind("lg_output", &format!("array<{word}>"), output);
    m.element_count(counted);
    let name = format!("{prefix}_scatter");
    let _ = write!(
        m.text,
        "{}    if (i >= lg_n()) {{ return; }}\n    let k = lg_keys[i];\n    var d = 0xffffffffu;\n    if (k < arrayLength(&lg_offsets)) {{ d = lg_offsets[k] + lg_slots[i]; }}\n    if (d >= arrayLength(&lg_output) / {w}u) {{\n        atomicAdd(&lg_control[{overflow}], 1u);\n        return;\n    }}\n{copy}}}\n",
        element_entry(&name)
    );
    m.finish(name, Groups::elements(WORKGROUP as u64))
}

/// The WGSL type an element of `w` words moves in, and how many of them: 16-byte vectors where
/// `w` is a multiple of 4, words otherwise.
fn moved_words(w: u32) -> (&'static str, u32) {
    if w.is_multiple_of(4) {
        ("vec4<u32>", w / 4)
    } else {
        ("u32", w)
    }
}

/// The gather over `buffers` (indices, input, output) of elements of `w` words: each element
/// from the place its index names, written in order, one thread per moved word (16-byte
/// vectors as the scatter's), so that a warp's stores are contiguous and the threads of one
/// element read its words together. An index past the input is counted as skipped.
fn gather_kernel(
    prefix: &str,
    buffers: [BufferRef; 3],
    counted: Option<ResourceId>,
    w: u32,
    overflow: u32,
) -> OpKernel {
    let mut m = Module::new(true);
    let [indices, input, output] = buffers;
    let (word, w) = moved_words(w);
    m.bind("lg_indices", "array<u32>", indices);
    m.bind("lg_input", &format!("array<{word}>"), input);
    m.bind("lg_output", &format!("array<{word}>"), output);
    m.element_count(counted);
    let name = format!("{prefix}_gather");
    // Thread `i` moves word `k` of element `e`.
    let _ = write!(
        m.text,
        "{}    let e = i / {w}u;\n    let k = i - e * {w}u;\n    if (e >= lg_n()) {{ return; }}\n    let s = lg_indices[e];\n    if (s >= arrayLength(&lg_input) / {w}u || e >= arrayLength(&lg_output) / {w}u) {{\n        if (k == 0u) {{ atomicAdd(&lg_control[{overflow}], 1u); }}\n        return;\n    }}\n    lg_output[i] = lg_input[s * {w}u + k];\n}}\n",
        element_entry(&name)
    );
    let groups = Groups {
        per_tile: Some((1, w as u64)),
        ..Groups::elements(WORKGROUP as u64)
    };
    m.finish(name, groups)
}
