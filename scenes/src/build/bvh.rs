//! BVH building: obvhs builds a BVH2 over the primitives' boxes on the CPU; we bound its depth
//! ([`limit_depth`]) and flatten it into nodes that hold both children's boxes, with primitives
//! reordered into leaf order.

use crate::gpu::GpuBvhNode;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2};
use std::time::Duration;

/// Deepest tree (in node levels, the root being level 1) the build makes: the WGSL traversal's
/// stack has as many entries, and a tree needs one fewer than its depth.
pub const MAX_DEPTH: usize = 64;

/// Which acceleration structure a compiled scene carries (and the WGSL traverses).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// A binary BVH ([`build`], [`GpuBvhNode`]).
    #[default]
    Bvh2,
    /// A compressed eight-wide BVH ([`crate::build::cwbvh::build`], [`crate::gpu::GpuCwbvhNode`]).
    Cwbvh,
}

impl BvhKind {
    /// The kind's name on the command line (`--bvh`) and in layout hints.
    pub fn name(self) -> &'static str {
        match self {
            BvhKind::Bvh2 => "bvh2",
            BvhKind::Cwbvh => "cwbvh",
        }
    }

    /// The WGSL preprocessor flag that selects this kind's node struct and traversal.
    pub fn flag(self) -> Option<&'static str> {
        match self {
            BvhKind::Bvh2 => None,
            BvhKind::Cwbvh => Some("CWBVH"),
        }
    }
}

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

/// obvhs's build settings for both BVHs: its slowest preset, whose reinsertion passes over
/// every node (ratio 1) cost Sponza's 262 k triangles 0.25 s more to build than its medium
/// preset and made PT 1.7-4.7% faster on an H100 (docs/performance.md, "BVH build quality").
pub const BUILD: BvhBuildParams = BvhBuildParams::very_slow_build();

/// Builds a BVH over `boxes` (min, max per primitive).
pub fn build(boxes: &[(Vec3A, Vec3A)]) -> Result<Bvh, String> {
    if boxes.is_empty() {
        return Err("cannot build a BVH over no primitives".into());
    }
    let aabbs: Vec<Aabb> = boxes.iter().map(|(lo, hi)| Aabb::new(*lo, *hi)).collect();
    let mut bvh2 = build_bvh2(&aabbs, BUILD, &mut Duration::default());
    limit_depth(&mut bvh2, MAX_DEPTH);
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
        // A single leaf: a root with the leaf as both children. The traversal has no empty
        // child (its slab test takes an inverted box for one that holds everything, and an
        // inner child would be a node to descend to); testing the primitives twice finds no
        // other hit.
        let i = push_inner(&mut nodes);
        let n = &mut nodes[i];
        n.left_min = root.aabb.min.into();
        n.left_max = root.aabb.max.into();
        n.left_first = root.first_index;
        n.left_count = root.prim_count;
        n.right_min = n.left_min;
        n.right_max = n.left_max;
        n.right_count = root.prim_count;
        n.right_first = root.first_index;
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
    debug_assert!(depth <= MAX_DEPTH, "the BVH is {depth} levels deep");
    Ok(Bvh {
        nodes,
        order: bvh2.primitive_indices.clone(),
        depth,
    })
}

/// Per node of `nodes`, its levels of inner nodes (0 for a leaf) and its number of leaves.
fn subtree_sizes(nodes: &[Bvh2Node]) -> (Vec<usize>, Vec<usize>) {
    let (mut levels, mut leaves) = (vec![0; nodes.len()], vec![1; nodes.len()]);
    // Depth-first from the root: in reverse, children come before their parent.
    let mut order = Vec::with_capacity(nodes.len());
    let mut stack = vec![0];
    while let Some(i) = stack.pop() {
        order.push(i);
        if !nodes[i].is_leaf() {
            let first = nodes[i].first_index as usize;
            stack.extend([first, first + 1]);
        }
    }
    for &i in order.iter().rev() {
        if !nodes[i].is_leaf() {
            let first = nodes[i].first_index as usize;
            levels[i] = 1 + levels[first].max(levels[first + 1]);
            leaves[i] = leaves[first] + leaves[first + 1];
        }
    }
    (levels, leaves)
}

/// Levels of inner nodes on the longest path of `bvh2` (0 when the root is a leaf).
pub(crate) fn depth(bvh2: &Bvh2) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0, 0)];
    while let Some((i, d)) = stack.pop() {
        let n = &bvh2.nodes[i];
        if !n.is_leaf() {
            deepest = deepest.max(d + 1);
            let first = n.first_index as usize;
            stack.extend([(first, d + 1), (first + 1, d + 1)]);
        }
    }
    deepest
}

/// Levels of inner nodes that `leaves` leaves need at least.
fn levels_for(leaves: usize) -> usize {
    leaves.next_power_of_two().trailing_zeros() as usize
}

/// Rebuilds the subtrees of `bvh2` that reach deeper than `max_depth` levels of inner nodes,
/// each from the deepest node whose children could not both be rebuilt in the levels left
/// below it: its leaves, in tree order, are split where the surface area heuristic puts the
/// cut among the cuts that leave both sides within their levels. Leaves, the primitive order
/// and subtrees within the depth stay as they are. A tree of at most 2^`max_depth` leaves
/// always fits.
pub(crate) fn limit_depth(bvh2: &mut Bvh2, max_depth: usize) {
    if depth(bvh2) <= max_depth {
        return;
    }
    let (levels, leaves) = subtree_sizes(&bvh2.nodes);
    assert!(
        levels_for(leaves[0]) <= max_depth,
        "{} leaves in {max_depth} levels",
        leaves[0]
    );
    let src = &bvh2.nodes;
    let mut nodes = vec![Bvh2Node::default()];
    // (source node, its place in `nodes`, the levels of inner nodes it may use); every subtree
    // queued fits its levels once rebuilt.
    let mut stack = vec![(0, 0, max_depth)];
    while let Some((i, at, budget)) = stack.pop() {
        let n = src[i];
        let first = n.first_index as usize;
        let kept =
            n.is_leaf() || levels[i] <= budget || levels_for(leaves[first]).max(levels_for(leaves[first + 1])) < budget;
        if !kept {
            rebuild(src, i, budget, at, &mut nodes);
        } else if n.is_leaf() {
            nodes[at] = n;
        } else {
            nodes[at] = Bvh2Node::new(n.aabb, 0, nodes.len() as u32);
            stack.extend([
                (first, nodes.len(), budget - 1),
                (first + 1, nodes.len() + 1, budget - 1),
            ]);
            nodes.extend([Bvh2Node::default(); 2]);
        }
    }
    bvh2.nodes = nodes;
    // Both index nodes, which moved.
    bvh2.parents.clear();
    bvh2.primitives_to_nodes.clear();
}

/// Writes a tree of at most `budget` levels of inner nodes over the leaves of `src[root]` to
/// `nodes[at]` and nodes appended to `nodes` ([`limit_depth`]).
fn rebuild(src: &[Bvh2Node], root: usize, budget: usize, at: usize, nodes: &mut Vec<Bvh2Node>) {
    let mut leaves = Vec::new();
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        let n = src[i];
        if n.is_leaf() {
            leaves.push(n);
        } else {
            stack.extend([n.first_index as usize + 1, n.first_index as usize]);
        }
    }
    // (leaves lo..hi, their place in `nodes`, their levels of inner nodes)
    let mut ranges = vec![(0, leaves.len(), at, budget)];
    let mut right = Vec::new();
    while let Some((lo, hi, at, budget)) = ranges.pop() {
        if hi - lo == 1 {
            nodes[at] = leaves[lo];
            continue;
        }
        let part = &leaves[lo..hi];
        // right[k]: the box of part[k..] and its primitives.
        right.clear();
        right.extend(part.iter().rev().scan((Aabb::empty(), 0), |acc, l| {
            *acc = (acc.0.union(&l.aabb), acc.1 + l.prim_count);
            Some(*acc)
        }));
        right.reverse();
        // Each side holds at most 2^(budget - 1) leaves; among the cheapest cuts, the most even.
        let side = 1usize.checked_shl(budget as u32 - 1).unwrap_or(usize::MAX);
        let cuts = part.len().saturating_sub(side).max(1)..side.min(part.len() - 1) + 1;
        let (mut left, mut best) = ((Aabb::empty(), 0), (f32::INFINITY, usize::MAX, 0));
        for k in 1..part.len() {
            left = (left.0.union(&part[k - 1].aabb), left.1 + part[k - 1].prim_count);
            if cuts.contains(&k) {
                let cost = left.0.half_area() * left.1 as f32 + right[k].0.half_area() * right[k].1 as f32;
                let unevenness = (2 * k).abs_diff(part.len());
                if (cost, unevenness) < (best.0, best.1) {
                    best = (cost, unevenness, k);
                }
            }
        }
        let cut = lo + best.2;
        nodes[at] = Bvh2Node::new(right[0].0, 0, nodes.len() as u32);
        ranges.extend([
            (lo, cut, nodes.len(), budget - 1),
            (cut, hi, nodes.len() + 1, budget - 1),
        ]);
        nodes.extend([Bvh2Node::default(); 2]);
    }
}

impl GpuBvhNode {
    fn zeroed_node() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn boxes(n: usize) -> Vec<(Vec3A, Vec3A)> {
        (0..n)
            .map(|i| {
                let p = Vec3A::new(i as f32, (i * 7 % 13) as f32, (i * 3 % 5) as f32);
                (p, p + Vec3A::splat(0.5))
            })
            .collect()
    }

    /// Boxes obvhs builds very deep trees over: 500 cubes nested around one point, shrinking
    /// by 0.97 (the surface area heuristic peels them off one by one), and 300 overlapping
    /// segments along a line (zero area: every tree costs nothing, obvhs chains them).
    pub(crate) fn deep_boxes() -> Vec<(Vec3A, Vec3A)> {
        let nest = (0..500).map(|k| {
            let s = 10.0 * 0.97f32.powi(k);
            let c = Vec3A::new(0.3, 0.1, -0.2) * s;
            (c - Vec3A::splat(s), c + Vec3A::splat(s))
        });
        let line = (0..300).map(|k| {
            let x = 20.0 + k as f32 * 0.01;
            (Vec3A::new(x, 1.0, 1.0), Vec3A::new(x + 0.1, 1.0, 1.0))
        });
        nest.chain(line).collect()
    }

    fn obvhs_bvh2(boxes: &[(Vec3A, Vec3A)]) -> Bvh2 {
        let aabbs: Vec<Aabb> = boxes.iter().map(|(lo, hi)| Aabb::new(*lo, *hi)).collect();
        build_bvh2(&aabbs, BUILD, &mut Duration::default())
    }

    #[test]
    fn leaves_cover_each_primitive_once() {
        for n in [1usize, 2, 3, 100, 1000] {
            assert_covers(&boxes(n));
        }
    }

    #[test]
    fn deep_trees_are_built_within_the_stack() {
        let b = deep_boxes();
        let unlimited = depth(&obvhs_bvh2(&b));
        assert!(
            unlimited > 2 * MAX_DEPTH,
            "obvhs's tree is only {unlimited} levels deep"
        );
        assert_covers(&b);
    }

    /// Walking the flattened nodes from the root reaches every node once and every primitive
    /// once, each child box contains its node's child boxes or primitives, and the tree is at
    /// most [`MAX_DEPTH`] levels deep.
    fn assert_covers(b: &[(Vec3A, Vec3A)]) {
        let n = b.len();
        let bvh = build(b).unwrap();
        let contains =
            |lo: [f32; 3], hi: [f32; 3], (plo, phi): (Vec3A, Vec3A)| (0..3).all(|k| lo[k] <= plo[k] && phi[k] <= hi[k]);
        let mut seen = vec![0u32; n];
        let mut nodes_seen = vec![0u32; bvh.nodes.len()];
        let mut stack = vec![(0usize, 1usize)];
        let mut depth = 0;
        while let Some((index, d)) = stack.pop() {
            nodes_seen[index] += 1;
            depth = depth.max(d);
            let node = &bvh.nodes[index];
            // A tree of one leaf has it as both children of the root: the right is seen once.
            let single_leaf =
                node.left_count > 0 && (node.left_first, node.left_count) == (node.right_first, node.right_count);
            for (lo, hi, first, count) in [
                (node.left_min, node.left_max, node.left_first, node.left_count),
                (node.right_min, node.right_max, node.right_first, node.right_count),
            ]
            .into_iter()
            .take(if single_leaf { 1 } else { 2 })
            {
                if count == 0 {
                    let child = &bvh.nodes[first as usize];
                    for (clo, chi) in [(child.left_min, child.left_max), (child.right_min, child.right_max)] {
                        let inside = contains(lo, hi, (Vec3A::from(clo), Vec3A::from(chi)));
                        assert!(inside, "n = {n}: a child box must contain its node's boxes");
                    }
                    stack.push((first as usize, d + 1));
                    continue;
                }
                for i in first..first + count {
                    let orig = bvh.order[i as usize] as usize;
                    seen[orig] += 1;
                    assert!(
                        contains(lo, hi, b[orig]),
                        "n = {n}: a leaf box must contain its primitive"
                    );
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "n = {n}: {seen:?}");
        assert!(nodes_seen.iter().all(|&s| s == 1), "n = {n}: nodes {nodes_seen:?}");
        assert_eq!(depth, bvh.depth);
        assert!((1..=MAX_DEPTH).contains(&bvh.depth), "n = {n}: {} levels", bvh.depth);
    }

    /// [`limit_depth`] to every depth from the least its leaves need up: the same leaves in a
    /// tree within the depth whose boxes contain their children's, the tree unchanged when
    /// already within it.
    #[test]
    fn limit_depth_keeps_the_leaves_within_the_depth() {
        let tree = obvhs_bvh2(&deep_boxes());
        let leaves = |t: &Bvh2| {
            let mut l: Vec<(u32, u32)> = t
                .nodes
                .iter()
                .filter(|n| n.is_leaf())
                .map(|n| (n.first_index, n.prim_count))
                .collect();
            l.sort();
            l
        };
        let all = leaves(&tree);
        let full = depth(&tree);
        for max in levels_for(all.len())..=full + 1 {
            let mut t = tree.clone();
            limit_depth(&mut t, max);
            assert!(depth(&t) <= max, "limited to {max}: {} levels", depth(&t));
            assert_eq!(leaves(&t), all, "limited to {max}");
            assert_eq!(
                t.nodes.len(),
                2 * all.len() - 1,
                "limited to {max}: every node in the tree"
            );
            for n in t.nodes.iter().filter(|n| !n.is_leaf()) {
                for c in [&t.nodes[n.first_index as usize], &t.nodes[n.first_index as usize + 1]] {
                    assert!(
                        n.aabb.union(&c.aabb) == n.aabb,
                        "limited to {max}: a box must contain its children's"
                    );
                }
            }
            if max >= full {
                assert!(bytemuck::cast_slice::<_, u8>(&t.nodes) == bytemuck::cast_slice::<_, u8>(&tree.nodes));
            }
        }
    }
}
