//! The acceleration structure over a scene's primitives: their boxes, clipped to
//! [`TRACED_EXTENT`], and a BVH of either kind over them.

use super::bvh::{self, BvhKind};
use super::cwbvh;
use crate::gpu::{GpuPrimitive, primitive_kind};
use glam::Vec3A;

/// How far from the origin the BVH bounds geometry. Beyond it, primitive boxes are clipped
/// (rays do not find the parts of primitives out there): the builders' surface areas stay
/// finite in f32, and f32 positions that far apart are coarser than 1e8 units anyway.
pub const TRACED_EXTENT: f32 = 1e15;

/// The primitives' boxes as the BVH bounds them (clipped to ±[`TRACED_EXTENT`]), and how many
/// were clipped.
pub(crate) fn traced_boxes(prims: &[GpuPrimitive]) -> (Vec<(Vec3A, Vec3A)>, usize) {
    let limit = Vec3A::splat(TRACED_EXTENT);
    let mut clipped = 0;
    let boxes = prims
        .iter()
        .map(|p| {
            let (a, b) = primitive_bounds(p);
            if a.min_element() < -TRACED_EXTENT || b.max_element() > TRACED_EXTENT {
                clipped += 1;
            }
            (a.clamp(-limit, limit), b.clamp(-limit, limit))
        })
        .collect();
    (boxes, clipped)
}

/// A BVH of `kind` over `boxes`: its nodes' bytes, the leaf order of the boxes and its depth.
pub(crate) fn build_bvh(kind: BvhKind, boxes: &[(Vec3A, Vec3A)]) -> Result<(Vec<u8>, Vec<u32>, usize), String> {
    Ok(match kind {
        BvhKind::Bvh2 => {
            let b = bvh::build(boxes)?;
            (bytemuck::cast_slice(&b.nodes).to_vec(), b.order, b.depth)
        }
        BvhKind::Cwbvh => {
            let b = cwbvh::build(boxes)?;
            (bytemuck::cast_slice(&b.nodes).to_vec(), b.order, b.depth)
        }
    })
}

/// The axis-aligned bounds of a primitive.
pub fn primitive_bounds(p: &GpuPrimitive) -> (Vec3A, Vec3A) {
    let a = Vec3A::from_array(p.a);
    if p.kind == primitive_kind::SPHERE {
        let r = Vec3A::splat(p.b[0]);
        (a - r, a + r)
    } else {
        let (b, c) = (a + Vec3A::from_array(p.b), a + Vec3A::from_array(p.c));
        (a.min(b).min(c), a.max(b).max(c))
    }
}
