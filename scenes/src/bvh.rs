//! BVH building: obvhs builds a BVH2 over the primitives' boxes on the CPU; we flatten it
//! into nodes that hold both children's boxes, with primitives reordered into leaf order.

use crate::gpu::GpuBvhNode;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2};
use std::time::Duration;

/// Deepest traversal stack the WGSL traversal supports.
pub const MAX_DEPTH: usize = 64;

/// Which acceleration structure a compiled scene carries (and the WGSL traverses).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// A binary BVH ([`build`], [`GpuBvhNode`]).
    #[default]
    Bvh2,
    /// A compressed eight-wide BVH ([`crate::cwbvh::build`], [`crate::gpu::GpuCwbvhNode`]).
    Cwbvh,
}

impl BvhKind {
    /// The WGSL preprocessor flag that selects this kind's node struct and traversal.
    pub fn flag(self) -> Option<&'static str> {
        match self {
            BvhKind::Bvh2 => None,
            BvhKind::Cwbvh => Some("CWBVH"),
        }
    }
}

const EMPTY_MIN: [f32; 3] = [1e30; 3];
const EMPTY_MAX: [f32; 3] = [-1e30; 3];

/// A built BVH: nodes (root first) and the primitive order leaves refer to.
#[derive(Debug, Clone)]
pub struct Bvh {
    /// Nodes, root at index 0.
    pub nodes: Vec<GpuBvhNode>,
    /// `order[i]` is the original index of the primitive stored at position `i`.
    pub order: Vec<u32>,
    /// Depth of the deepest leaf.
    pub depth: usize,
}

/// Builds a BVH over `boxes` (min, max per primitive).
pub fn build(boxes: &[(Vec3A, Vec3A)]) -> Result<Bvh, String> {
    if boxes.is_empty() {
        return Err("cannot build a BVH over no primitives".into());
    }
    let aabbs: Vec<Aabb> = boxes.iter().map(|(lo, hi)| Aabb::new(*lo, *hi)).collect();
    let bvh2 = build_bvh2(&aabbs, BvhBuildParams::medium_build(), &mut Duration::default());
    let src = &bvh2.nodes;
    let child = |i: usize| -> (Aabb, u32, u32) {
        let n = &src[i];
        (n.aabb, n.first_index, n.prim_count)
    };
    let mut nodes: Vec<GpuBvhNode> = Vec::with_capacity(src.len() / 2 + 1);
    let mut depth = 0;
    // (obvhs node index of an inner node, our node index, depth)
    let mut stack: Vec<(usize, usize, usize)> = Vec::new();
    let push_inner = |nodes: &mut Vec<GpuBvhNode>| -> usize {
        nodes.push(GpuBvhNode::zeroed_node());
        nodes.len() - 1
    };
    let root = &src[0];
    if root.prim_count > 0 {
        // A single leaf: a root whose right child is empty.
        let i = push_inner(&mut nodes);
        let n = &mut nodes[i];
        n.left_min = root.aabb.min.into();
        n.left_max = root.aabb.max.into();
        n.left_first = root.first_index;
        n.left_count = root.prim_count;
        n.right_min = EMPTY_MIN;
        n.right_max = EMPTY_MAX;
        n.right_count = 0;
        n.right_first = u32::MAX;
        depth = 1;
    } else {
        let i = push_inner(&mut nodes);
        stack.push((0, i, 1));
    }
    while let Some((src_index, dst, d)) = stack.pop() {
        depth = depth.max(d);
        let first = src[src_index].first_index as usize;
        let mut refs = [(0u32, 0u32); 2];
        for (side, c) in [first, first + 1].into_iter().enumerate() {
            let (_, first_index, count) = child(c);
            refs[side] = if count > 0 {
                (first_index, count)
            } else {
                let j = push_inner(&mut nodes);
                stack.push((c, j, d + 1));
                (j as u32, 0)
            };
        }
        let (l, r) = (child(first).0, child(first + 1).0);
        let n = &mut nodes[dst];
        n.left_min = l.min.into();
        n.left_max = l.max.into();
        n.left_first = refs[0].0;
        n.left_count = refs[0].1;
        n.right_min = r.min.into();
        n.right_max = r.max.into();
        n.right_first = refs[1].0;
        n.right_count = refs[1].1;
    }
    if depth >= MAX_DEPTH {
        return Err(format!(
            "the BVH is {depth} levels deep; traversal supports {MAX_DEPTH}"
        ));
    }
    Ok(Bvh {
        nodes,
        order: bvh2.primitive_indices.clone(),
        depth,
    })
}

impl GpuBvhNode {
    fn zeroed_node() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize) -> Vec<(Vec3A, Vec3A)> {
        (0..n)
            .map(|i| {
                let p = Vec3A::new(i as f32, (i * 7 % 13) as f32, (i * 3 % 5) as f32);
                (p, p + Vec3A::splat(0.5))
            })
            .collect()
    }

    /// Every primitive is reachable exactly once, and every child box contains its leaves.
    #[test]
    fn leaves_cover_each_primitive_once() {
        for n in [1usize, 2, 3, 100, 1000] {
            let b = boxes(n);
            let bvh = build(&b).unwrap();
            let mut seen = vec![0u32; n];
            for node in &bvh.nodes {
                for (lo, hi, first, count) in [
                    (node.left_min, node.left_max, node.left_first, node.left_count),
                    (node.right_min, node.right_max, node.right_first, node.right_count),
                ] {
                    for i in first..first + count {
                        let orig = bvh.order[i as usize] as usize;
                        seen[orig] += 1;
                        let (plo, phi) = b[orig];
                        assert!(
                            (0..3).all(|k| lo[k] <= plo[k] && phi[k] <= hi[k]),
                            "leaf box must contain its primitive"
                        );
                    }
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "n = {n}: {seen:?}");
        }
    }
}
