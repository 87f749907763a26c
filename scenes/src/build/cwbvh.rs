//! Compressed wide BVH building (Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal
//! on GPUs Through Compressed Wide BVHs", HPG 2017): obvhs builds an eight-wide BVH with
//! quantized child boxes and leaves of at most three primitives, from a binary tree whose
//! depth we bound until the wide one fits the traversal stack ([`MAX_DEPTH`]); we pack its nodes
//! into u32 words for WGSL ([`GpuCwbvhNode`]), with primitives reordered into leaf order.

use crate::build::bvh;
use crate::gpu::GpuCwbvhNode;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ploc::PlocBuilder;

/// Deepest tree (in node levels, the root being level 1) the build makes: the WGSL traversal's
/// stack has as many entries, and a tree needs one fewer than its depth.
pub const MAX_DEPTH: usize = 32;

/// A built compressed wide BVH: nodes (root first) and the primitive order leaves refer to.
#[derive(Debug, Clone)]
pub struct Cwbvh {
    /// Nodes, root at index 0.
    pub nodes: Vec<GpuCwbvhNode>,
    /// `order[i]` is the original index of the primitive stored at position `i`.
    pub order: Vec<u32>,
    /// Number of node levels on the longest path from the root.
    pub depth: usize,
}

/// Builds a compressed wide BVH over `boxes` (min, max per primitive).
pub fn build(boxes: &[(Vec3A, Vec3A)]) -> Result<Cwbvh, String> {
    if boxes.is_empty() {
        return Err("cannot build a BVH over no primitives".into());
    }
    // obvhs quantizes a child's box relative to its node in f32, which can cut it by a rounding
    // step of the difference, up to 2^-24 x 255 x the node's grid step: the WGSL traversal's
    // margin covers that. Its build_cwbvh checks the quantized boxes with an absolute tolerance
    // of 1e-5 in debug builds (a panic, with coordinates in the millions), so we build as it
    // does, without that check.
    let aabbs: Vec<Aabb> = boxes.iter().map(|(lo, hi)| Aabb::new(*lo, *hi)).collect();
    let params = bvh::BUILD;
    let mut bvh2 = binary_tree(&aabbs, &params);
    // A wide node spans at most seven binary levels of inner nodes and a leaf two: a binary
    // tree deeper than this cannot fit (and could overflow the recursion of obvhs's conversion).
    bvh::limit_depth(&mut bvh2, 7 * MAX_DEPTH + 2);
    let convert = |bvh2: &Bvh2| bvh2_to_cwbvh(bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
    let mut cwbvh = convert(&bvh2);
    let mut depth = wide_depth(&cwbvh.nodes);
    // A wide node spans at least one binary level, so a binary tree of MAX_DEPTH levels fits:
    // shorten the binary tree in proportion to the excess until the wide one fits.
    while depth > MAX_DEPTH {
        let binary = bvh::depth(&bvh2);
        bvh::limit_depth(&mut bvh2, (binary * MAX_DEPTH / depth).max(MAX_DEPTH));
        cwbvh = convert(&bvh2);
        depth = wide_depth(&cwbvh.nodes);
    }
    Ok(Cwbvh {
        nodes: cwbvh.nodes.iter().map(pack).collect(),
        order: cwbvh.primitive_indices,
        depth,
    })
}

/// obvhs's binary tree over `aabbs`, one primitive per leaf as its conversion needs.
fn binary_tree(aabbs: &[Aabb], params: &BvhBuildParams) -> Bvh2 {
    let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2
}

/// Packs eight bytes into two little-endian words.
fn words(bytes: [u8; 8]) -> [u32; 2] {
    [
        u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]),
    ]
}

const _: () = assert!(size_of::<GpuCwbvhNode>() == size_of::<CwBvhNode>());

/// Packs an obvhs node into u32 words, byte for byte.
fn pack(n: &CwBvhNode) -> GpuCwbvhNode {
    GpuCwbvhNode {
        p: n.p.into(),
        e_imask: u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]),
        child_base: n.child_base_idx,
        primitive_base: n.primitive_base_idx,
        child_meta: words(n.child_meta),
        child_min_x: words(n.child_min_x),
        child_max_x: words(n.child_max_x),
        child_min_y: words(n.child_min_y),
        child_max_y: words(n.child_max_y),
        child_min_z: words(n.child_min_z),
        child_max_z: words(n.child_max_z),
    }
}

/// Node levels on the longest path from the root.
fn wide_depth(nodes: &[CwBvhNode]) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((index, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = &nodes[index];
        for slot in 0..8 {
            if n.imask & (1 << slot) != 0 {
                stack.push((n.child_node_index(slot) as usize, d + 1));
            }
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Byte `i` of a packed pair of words, as the WGSL traversal reads it.
    fn byte(w: [u32; 2], i: usize) -> u32 {
        (w[i / 4] >> ((i % 4) * 8)) & 0xff
    }

    /// Boxes of varied sizes, some flat (like axis-aligned walls), some repeated.
    fn boxes(n: usize) -> Vec<(Vec3A, Vec3A)> {
        (0..n)
            .map(|i| {
                let p = Vec3A::new((i % 97) as f32 * 0.37, (i * 7 % 13) as f32, (i * 3 % 5) as f32 - 2.0);
                let size = Vec3A::new(
                    0.01 + (i % 5) as f32,
                    if i % 4 == 0 { 0.0 } else { 0.5 },
                    (i % 3) as f32 * 0.25,
                );
                (p, p + size)
            })
            .collect()
    }

    #[test]
    fn leaves_cover_each_primitive_once() {
        for n in [1usize, 2, 3, 4, 9, 100, 1000, 5000] {
            assert_covers(&boxes(n));
        }
    }

    /// Boxes in a box of 2 units beside one reaching 2^25 down (found by fuzzing: obvhs's debug
    /// check panicked, "Primitive 26 does not fit in parent 1", a quantized box was cut by 1.2).
    #[test]
    fn boxes_far_from_the_origin_are_covered() {
        let mut b: Vec<(Vec3A, Vec3A)> = (0..20)
            .map(|i| {
                let (x, z) = ((i % 5) as f32 * 0.4 - 1.0, (i / 5) as f32 * 0.3 - 1.0);
                let top = [1.2, 1.99, 0.7, 1.59][i % 4];
                (Vec3A::new(x, 0.0, z), Vec3A::new(x + 0.5, top, z + 0.2))
            })
            .collect();
        b.push((Vec3A::new(-0.7, -33554432.0, -0.6), Vec3A::new(-0.1, 1.2, -0.4)));
        assert_covers(&b);
    }

    /// Walking the packed nodes from the root reaches every node and every primitive of `b`
    /// exactly once, and each child's dequantized box contains its primitives to the rounding
    /// the builder's quantization allows (2^-24 x 255 x the grid step, which the traversal's
    /// margin covers).
    fn assert_covers(b: &[(Vec3A, Vec3A)]) {
        let n = b.len();
        let bvh = build(b).unwrap();
        let mut seen = vec![0u32; n];
        let mut nodes_seen = vec![0u32; bvh.nodes.len()];
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            nodes_seen[index] += 1;
            let node = &bvh.nodes[index];
            let imask = node.e_imask >> 24;
            let e: [f64; 3] = [0, 8, 16].map(|s| f32::from_bits(((node.e_imask >> s) & 0xff) << 23) as f64);
            let mut inner = 0;
            for i in 0..8 {
                let meta = byte(node.child_meta, i);
                if meta == 0 {
                    assert_eq!(imask & (1 << i), 0, "an empty slot is no inner node");
                    continue;
                }
                let q = [
                    (node.child_min_x, node.child_max_x),
                    (node.child_min_y, node.child_max_y),
                    (node.child_min_z, node.child_max_z),
                ];
                let lo: [f64; 3] = std::array::from_fn(|k| node.p[k] as f64 + byte(q[k].0, i) as f64 * e[k]);
                let hi: [f64; 3] = std::array::from_fn(|k| node.p[k] as f64 + byte(q[k].1, i) as f64 * e[k]);
                if imask & (1 << i) != 0 {
                    assert_eq!(meta, 0b0010_0000 | (24 + i as u32), "inner meta byte");
                    stack.push(node.child_base as usize + inner);
                    inner += 1;
                    continue;
                }
                let first = node.primitive_base + (meta & 0b1_1111);
                let count = meta >> 5;
                assert!(matches!(count, 0b1 | 0b11 | 0b111), "unary count {count:#b}");
                for j in first..first + count.count_ones() {
                    let orig = bvh.order[j as usize] as usize;
                    seen[orig] += 1;
                    let (plo, phi) = b[orig];
                    for k in 0..3 {
                        let tol = 0.5 * f32::EPSILON as f64 * 255.0 * e[k];
                        assert!(
                            lo[k] <= plo[k] as f64 + tol && phi[k] as f64 - tol <= hi[k],
                            "n = {n}: the box of leaf {i} of node {index} must contain primitive {orig}"
                        );
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "n = {n}: {seen:?}");
        assert!(nodes_seen.iter().all(|&s| s == 1), "n = {n}: nodes {nodes_seen:?}");
        assert!((1..=MAX_DEPTH).contains(&bvh.depth));
    }

    /// obvhs's binary tree over these boxes is deeper than any that converts within
    /// [`MAX_DEPTH`] wide levels.
    #[test]
    fn deep_trees_are_built_within_the_stack() {
        let b = crate::build::bvh::tests::deep_boxes();
        let aabbs: Vec<Aabb> = b.iter().map(|(lo, hi)| Aabb::new(*lo, *hi)).collect();
        let unlimited = bvh::depth(&binary_tree(&aabbs, &bvh::BUILD));
        assert!(
            unlimited > 7 * MAX_DEPTH + 2,
            "obvhs's tree is only {unlimited} levels deep"
        );
        assert_covers(&b);
    }

    #[test]
    fn no_primitives_is_an_error() {
        assert!(build(&[]).is_err());
    }
}
