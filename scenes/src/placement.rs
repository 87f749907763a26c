//! Copies of a scene's glTF asset placed by transforms (`gltf_instances` of a RON scene): each
//! copy's meshes are flattened into the scene's shapes, so a small asset makes a scene of as
//! many triangles as a test of scale needs.

use crate::model::{Shape, Vec3};
use glam::{Affine3A, Quat, Vec3A};
use serde::Deserialize;

/// Where copies of the glTF asset go.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub enum Placement {
    /// One copy, scaled uniformly, turned about the y axis, then moved.
    At {
        /// The move.
        #[serde(default)]
        translate: Vec3,
        /// The uniform scale (positive).
        #[serde(default = "unit_scale")]
        scale: f32,
        /// The turn about the y axis, in degrees.
        #[serde(default)]
        rotate_y_degrees: f32,
    },
    /// A grid of unscaled copies, `counts` along x, y and z, `spacing` apart, the first at
    /// the asset's own place.
    Grid {
        /// Copies along each axis (each at least 1).
        counts: (u32, u32, u32),
        /// Distance between neighbouring copies along each axis.
        spacing: Vec3,
    },
}

fn unit_scale() -> f32 {
    1.0
}

/// The most copies a scene may place (a guard against a typo's billions).
pub const MAX_COPIES: u64 = 1 << 20;

/// Checks `placements`: positive finite scales, finite moves and turns, grids of at least one
/// copy along each axis, at most [`MAX_COPIES`] in all. The error names the placement kind and
/// says what is wrong.
pub fn check(placements: &[Placement]) -> Result<(), (&'static str, String)> {
    let mut copies = 0u64;
    for p in placements {
        match p {
            Placement::At {
                translate,
                scale,
                rotate_y_degrees,
            } => {
                if !(*scale > 0.0 && scale.is_finite()) {
                    return Err(("scale", format!("gltf_instances: scale {scale} is not positive")));
                }
                if !(translate.iter().all(|t| t.is_finite()) && rotate_y_degrees.is_finite()) {
                    return Err((
                        "At",
                        "gltf_instances: a translate or rotate_y_degrees is not finite".into(),
                    ));
                }
                copies += 1;
            }
            Placement::Grid { counts, spacing } => {
                if counts.0 == 0 || counts.1 == 0 || counts.2 == 0 {
                    return Err((
                        "counts",
                        format!("gltf_instances: grid counts {counts:?} place no copy"),
                    ));
                }
                if !spacing.iter().all(|s| s.is_finite()) {
                    return Err(("spacing", "gltf_instances: a grid spacing is not finite".into()));
                }
                copies += counts.0 as u64 * counts.1 as u64 * counts.2 as u64;
            }
        }
    }
    if copies > MAX_COPIES {
        return Err((
            "gltf_instances",
            format!("gltf_instances places {copies} copies of the asset, more than {MAX_COPIES}"),
        ));
    }
    Ok(())
}

/// The transforms `placements` stand for, in order (a grid x fastest, then y, then z).
pub fn transforms(placements: &[Placement]) -> Vec<Affine3A> {
    let mut all = Vec::new();
    for p in placements {
        match p {
            Placement::At {
                translate,
                scale,
                rotate_y_degrees,
            } => all.push(Affine3A::from_scale_rotation_translation(
                glam::Vec3::splat(*scale),
                Quat::from_rotation_y(rotate_y_degrees.to_radians()),
                glam::Vec3::from(*translate),
            )),
            Placement::Grid { counts, spacing } => {
                for z in 0..counts.2 {
                    for y in 0..counts.1 {
                        for x in 0..counts.0 {
                            let at = glam::Vec3::new(x as f32, y as f32, z as f32) * glam::Vec3::from(*spacing);
                            all.push(Affine3A::from_translation(at));
                        }
                    }
                }
            }
        }
    }
    all
}

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

    #[test]
    fn bad_placements_are_refused() {
        let at = |scale| Placement::At {
            translate: [0.0; 3],
            scale,
            rotate_y_degrees: 0.0,
        };
        assert!(check(&[at(1.0)]).is_ok());
        assert!(check(&[at(0.0)]).unwrap_err().1.contains("scale 0"));
        assert!(check(&[at(f32::NAN)]).is_err());
        let grid = |counts| Placement::Grid {
            counts,
            spacing: [1.0; 3],
        };
        assert!(check(&[grid((2, 0, 2))]).unwrap_err().1.contains("place no copy"));
        assert!(check(&[grid((1024, 1024, 2))]).unwrap_err().1.contains("more than"));
    }
}
