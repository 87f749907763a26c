//! Copies of a scene's glTF asset placed by `gltf_instances`: each copy's meshes are flattened
//! into the scene's shapes, so a small asset makes a scene of as many triangles as a test of
//! scale needs.

use crate::model::placement::{Placement, transforms};
use crate::model::{Shape, Vec3};
use glam::{Affine3A, Vec3A};

/// `shapes` copied once for each of `placements`' transforms (unchanged when there are none).
pub fn place(shapes: Vec<Shape>, placements: &[Placement]) -> Vec<Shape> {
    if placements.is_empty() {
        return shapes;
    }
    let transforms = transforms(placements);
    let mut placed = Vec::with_capacity(shapes.len() * transforms.len());
    for t in &transforms {
        placed.extend(shapes.iter().map(|s| transformed(s, t)));
    }
    placed
}

/// `shape` under the similarity transform `t` (uniform scale, rotation, translation): its
/// points moved, its normals turned, a sphere's radius scaled.
fn transformed(shape: &Shape, t: &Affine3A) -> Shape {
    let point = |p: &Vec3| t.transform_point3a(Vec3A::from(*p)).to_array();
    let normal = |n: &Vec3| t.transform_vector3a(Vec3A::from(*n)).normalize_or_zero().to_array();
    let mut s = shape.clone();
    match &mut s {
        Shape::Triangle { vertices, .. } => vertices.iter_mut().for_each(|v| *v = point(v)),
        Shape::Quad { corners, .. } => corners.iter_mut().for_each(|v| *v = point(v)),
        Shape::Mesh {
            positions,
            normals,
            tangents,
            ..
        } => {
            positions.iter_mut().for_each(|v| *v = point(v));
            if let Some(normals) = normals {
                normals.iter_mut().for_each(|n| *n = normal(n));
            }
            // A similarity keeps the handedness of the tangent frames.
            for t in tangents.iter_mut().flatten().flatten() {
                let [x, y, z] = normal(&[t[0], t[1], t[2]]);
                *t = [x, y, z, t[3]];
            }
        }
        Shape::Sphere { center, radius, .. } => {
            *center = point(center);
            *radius *= t.matrix3.x_axis.length();
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_and_a_turned_copy_place_every_point() {
        let tri = Shape::Triangle {
            vertices: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            material: "m".into(),
            emission: None,
        };
        let placements = [
            Placement::Grid {
                counts: (2, 1, 3),
                spacing: [10.0, 0.0, 20.0],
            },
            Placement::At {
                translate: [0.0, 5.0, 0.0],
                scale: 2.0,
                rotate_y_degrees: 90.0,
            },
        ];
        let placed = place(vec![tri], &placements);
        assert_eq!(placed.len(), 7);
        let Shape::Triangle { vertices, .. } = &placed[5] else {
            panic!()
        };
        assert_eq!(vertices[0], [11.0, 0.0, 40.0], "grid copy (1, 0, 2)");
        let Shape::Triangle { vertices, .. } = &placed[6] else {
            panic!()
        };
        // (1, 0, 0) scaled by 2 and turned 90 degrees about y is (0, 0, -2); moved up by 5.
        let v = vertices[0];
        assert!(
            (v[0]).abs() < 1e-5 && (v[1] - 5.0).abs() < 1e-6 && (v[2] + 2.0).abs() < 1e-5,
            "{v:?}"
        );
    }
}
