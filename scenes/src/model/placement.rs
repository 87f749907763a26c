//! Copies of a scene's glTF asset placed by transforms (`gltf_instances` of a RON scene): the
//! placements, their checks and the transforms they stand for ([`crate::resolve::placement`]
//! places the copies).

use super::Vec3;
use glam::{Affine3A, Quat};
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

#[cfg(test)]
mod tests {
    use super::*;

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
