//! `<transform>` elements: `<matrix>` (16 numbers, row by row, or 9 for a 3x3 matrix),
//! `<translate>`, `<rotate>`, `<scale>` and `<lookat>`, each applied after the ones before
//! it (left-multiplied), as Mitsuba composes them.

use super::xml::{Context, Props, Result, numbers, point_of};
use glam::{Mat3, Mat4, Vec3};
use roxmltree::Node;

/// The matrix of a `<transform>` element.
pub fn parse(ctx: &mut Context, node: Node) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for op in node.children().filter(|c| c.is_element()) {
        let step = match op.tag_name().name() {
            "matrix" => {
                let text = ctx.attribute(op, "value")?;
                match numbers(&text).as_deref() {
                    Some(v) if v.len() == 16 => Mat4::from_cols_array(&std::array::from_fn(|i| v[(i % 4) * 4 + i / 4])),
                    Some(v) if v.len() == 9 => {
                        Mat4::from_mat3(Mat3::from_cols_array(&std::array::from_fn(|i| v[(i % 3) * 3 + i / 3])))
                    }
                    _ => return Err(ctx.error(op, "a matrix needs 16 (or 9) numbers")),
                }
            }
            "translate" => Mat4::from_translation(Vec3::from(point_of(ctx, op, 0.0)?)),
            "scale" => Mat4::from_scale(Vec3::from(point_of(ctx, op, 1.0)?)),
            "rotate" => {
                let angle = match ctx.optional_attribute(op, "angle")?.as_deref().map(numbers) {
                    Some(Some(v)) if v.len() == 1 => v[0],
                    _ => return Err(ctx.error(op, "a rotation needs an angle in degrees")),
                };
                let axis = Vec3::from(point_of(ctx, op, 0.0)?);
                if axis.length_squared() == 0.0 {
                    return Err(ctx.error(op, "a rotation needs an axis (x, y, z)"));
                }
                Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
            }
            "lookat" | "look_at" => {
                let vector = |ctx: &Context, key: &str| -> Result<Vec3> {
                    let text = ctx.attribute(op, key)?;
                    match numbers(&text).as_deref() {
                        Some([x, y, z]) => Ok(Vec3::new(*x, *y, *z)),
                        _ => Err(ctx.error(op, format!("{key}='{text}' is not three numbers"))),
                    }
                };
                let origin = vector(ctx, "origin")?;
                let target = vector(ctx, "target")?;
                let up = match ctx.optional_attribute(op, "up")? {
                    Some(_) => vector(ctx, "up")?,
                    None => Vec3::Y,
                };
                look_at(origin, target, up)
                    .ok_or_else(|| ctx.error(op, "the view direction is zero or parallel to the up direction"))?
            }
            _ => {
                ctx.warn(op, "an unknown transformation is ignored");
                Mat4::IDENTITY
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(ctx.error(node, "the transformation is not finite"));
    }
    Ok(m)
}

/// The `to_world` transform of a plugin (identity without one).
pub fn to_world(ctx: &mut Context, props: &Props) -> Result<Mat4> {
    match props.get("to_world") {
        Some(t) => parse(ctx, t),
        None => Ok(Mat4::IDENTITY),
    }
}

/// Mitsuba's look-at frame: local +Z looks at `target`, +Y is up and +X is
/// up × direction (the image's left); `None` when the frame is degenerate.
pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).normalize_or_zero();
    let left = up.cross(dir).normalize_or_zero();
    if dir == Vec3::ZERO || left == Vec3::ZERO {
        return None;
    }
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use roxmltree::Document;
    use std::path::Path;

    fn transform(inner: &str) -> Result<Mat4> {
        let text = format!("<transform name=\"to_world\">{inner}</transform>");
        let doc = Document::parse(&text).unwrap();
        let mut ctx = Context::new("t.xml", Path::new("."), &doc).unwrap();
        parse(&mut ctx, doc.root_element())
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn matrices_are_row_major() {
        let m = transform("<matrix value=\"1 0 0 5 0 1 0 6 0 0 1 7 0 0 0 1\"/>").unwrap();
        assert_eq!(m.transform_point3(Vec3::ZERO), Vec3::new(5.0, 6.0, 7.0));
        let m = transform("<matrix value=\"0 -1 0 1 0 0 0 0 1\"/>").unwrap();
        assert!(close(m.transform_vector3(Vec3::X), Vec3::Y));
    }

    #[test]
    fn operations_apply_in_order() {
        // Scale by 2, then rotate 90 degrees about z, then translate.
        let m = transform("<scale value=\"2\"/><rotate z=\"1\" angle=\"90\"/><translate x=\"1\" y=\"2\" z=\"3\"/>")
            .unwrap();
        assert!(close(m.transform_point3(Vec3::X), Vec3::new(1.0, 4.0, 3.0)));
        let m = transform("<scale x=\"2\"/><translate value=\"0 0 1\"/>").unwrap();
        assert!(close(m.transform_point3(Vec3::ONE), Vec3::new(2.0, 1.0, 2.0)));
    }

    #[test]
    fn look_at_puts_local_z_towards_the_target_and_x_to_the_left() {
        let m = transform("<lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>").unwrap();
        assert!(close(m.transform_point3(Vec3::ZERO), Vec3::new(0.0, 0.0, 5.0)));
        assert!(close(m.transform_vector3(Vec3::Z), Vec3::NEG_Z));
        // Looking down -Z with +Y up, the left is -X.
        assert!(close(m.transform_vector3(Vec3::X), Vec3::NEG_X));
    }

    #[test]
    fn malformed_transformations_are_errors_with_positions() {
        let e = transform("\n<matrix value=\"1 2 3\"/>").unwrap_err();
        assert_eq!(e.at, (2, 1));
        assert!(e.message.contains("16 (or 9) numbers"), "{}", e.message);
        let e = transform("<rotate angle=\"10\"/>").unwrap_err();
        assert!(e.message.contains("needs an axis"), "{}", e.message);
        let e = transform("<lookat origin=\"0 0 0\" target=\"0 1 0\"/>").unwrap_err();
        assert!(e.message.contains("parallel"), "{}", e.message);
    }
}
