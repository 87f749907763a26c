//! The camera a scene without one gets: framing its bounds.

use super::{Camera, FovAxis, Look, Scene, Shape};
use glam::Vec3;

/// A camera looking down -Z (glTF's default view) at the centre of the scene's bounding
/// sphere, far enough back for a vertical field of view of 45 degrees to hold all of it.
pub fn default_camera(scene: &Scene) -> Camera {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let mut add = |p: Vec3, r: f32| {
        if p.is_finite() && r.is_finite() {
            lo = lo.min(p - r);
            hi = hi.max(p + r);
        }
    };
    for shape in &scene.shapes {
        match shape {
            Shape::Triangle { vertices, .. } => vertices.iter().for_each(|&v| add(Vec3::from(v), 0.0)),
            Shape::Quad { corners, .. } => corners.iter().for_each(|&v| add(Vec3::from(v), 0.0)),
            Shape::Mesh { positions, .. } => positions.iter().for_each(|&v| add(Vec3::from(v), 0.0)),
            Shape::Sphere { center, radius, .. } => add(Vec3::from(*center), *radius),
        }
    }
    let (center, radius) = if lo.x <= hi.x {
        ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-6))
    } else {
        (Vec3::ZERO, 1.0)
    };
    let fov_degrees: f32 = 45.0;
    let distance = radius / (fov_degrees.to_radians() * 0.5).sin();
    Camera {
        position: (center + Vec3::Z * distance).to_array(),
        look: Look::Target(center.to_array()),
        up: [0.0, 1.0, 0.0],
        fov_degrees,
        fov_axis: FovAxis::Smaller,
        lens: None,
    }
}
