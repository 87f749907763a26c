//! The `perspective` sensor and its `film`: Mitsuba's camera looks along its local +Z with +Y
//! up and +X to the image's left (its look-at frame), which is lightgraph's camera
//! (right = forward x up) when `to_world` does not mirror; a mirroring one would flip the
//! image left to right and is warned about. `fov_axis` x, y and smaller map directly;
//! `diagonal` and `larger` are converted to the horizontal field of view of the film. The
//! medium the sensor is in is its nested `<medium>` ([`medium`]).

use super::transform;
use super::xml::{Context, Props, Result};
use crate::model::{Camera, FovAxis, Look, ThinLens};
use glam::{Mat4, Vec3};
use roxmltree::Node;

/// The camera and the image size (width, height) of a `<sensor>`.
pub fn sensor<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<(Camera, (u32, u32))> {
    let kind = ctx.plugin_type(node)?;
    let props = Props::new(node);
    let lens = match kind.as_str() {
        "perspective" => None,
        "thinlens" => thin_lens(ctx, &props)?,
        _ => return Err(ctx.error(node, "only perspective and thinlens sensors are supported")),
    };
    let size = match props.nested(ctx, "film")?.first() {
        Some(&film) => film_size(ctx, film)?,
        None => (768, 576),
    };
    // Read by `medium`.
    props.nested(ctx, "medium")?;
    let m = transform::to_world(ctx, &props)?;
    let left = m.transform_vector3(Vec3::X);
    let up = m.transform_vector3(Vec3::Y);
    let forward = m.transform_vector3(Vec3::Z);
    if left.cross(up).dot(forward) < 0.0 {
        ctx.warn(
            node,
            "to_world mirrors: lightgraph's image is Mitsuba's flipped left to right",
        );
    }
    if forward.normalize_or_zero() == Vec3::ZERO || forward.cross(up).normalize_or_zero() == Vec3::ZERO {
        return Err(ctx.error(node, "to_world gives no view direction and up direction"));
    }
    let fov = match (props.float(ctx, "fov")?, props.string(ctx, "focal_length")?) {
        (Some(fov), _) => fov,
        (None, focal) => {
            // Mitsuba: a focal length on 35 mm film (36 x 24 mm) spans the diagonal.
            let text = focal.unwrap_or_else(|| "50mm".into());
            let mm: f32 = text
                .trim_end_matches("mm")
                .trim()
                .parse()
                .map_err(|_| ctx.error(node, format!("focal_length '{text}' is not a length in mm")))?;
            let diagonal = (36f32.hypot(24.0) / (2.0 * mm)).atan().to_degrees() * 2.0;
            return finish(ctx, &props, (m, lens), diagonal, "diagonal", size);
        }
    };
    let axis = props.string(ctx, "fov_axis")?.unwrap_or_else(|| "x".into());
    finish(ctx, &props, (m, lens), fov, &axis, size)
}

/// The medium sensor `node` is in (a nested `<medium>` or a `<ref>` to one); none: vacuum.
pub fn medium<'a, 'i>(ctx: &Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Option<Node<'a, 'i>>> {
    match Props::new(node).nested(ctx, "medium")?[..] {
        [] => Ok(None),
        [one] => Ok(Some(one)),
        _ => Err(ctx.error(node, "a sensor is in one medium")),
    }
}

/// A `thinlens` sensor's lens: `aperture_radius` (required, as in Mitsuba 3) and
/// `focus_distance` (Mitsuba's default: the far clip distance, 10^4); `None` for a radius of 0.
fn thin_lens(ctx: &mut Context, props: &Props) -> Result<Option<ThinLens>> {
    let node = props.node();
    let Some(aperture_radius) = props.float(ctx, "aperture_radius")? else {
        return Err(ctx.error(node, "a thinlens sensor needs its aperture_radius"));
    };
    let far_clip = props.float(ctx, "far_clip")?.unwrap_or(1e4);
    let focus_distance = props.float(ctx, "focus_distance")?.unwrap_or(far_clip);
    if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
        return Err(ctx.error(node, format!("aperture_radius {aperture_radius} is not a radius")));
    }
    if !(focus_distance > 0.0 && focus_distance.is_finite()) {
        return Err(ctx.error(node, format!("focus_distance {focus_distance} is not a distance")));
    }
    Ok((aperture_radius > 0.0).then_some(ThinLens {
        aperture_radius,
        focus_distance,
    }))
}

/// The camera of `to_world` `m` with `lens`, a field of view `fov` across `axis`, and the film
/// `size`.
fn finish(
    ctx: &mut Context,
    props: &Props,
    (m, lens): (Mat4, Option<ThinLens>),
    fov: f32,
    axis: &str,
    size: (u32, u32),
) -> Result<(Camera, (u32, u32))> {
    let node = props.node();
    if !(fov > 0.0 && fov < 180.0) {
        return Err(ctx.error(
            node,
            format!("the field of view {fov} is not between 0 and 180 degrees"),
        ));
    }
    let (w, h) = (size.0 as f32, size.1 as f32);
    // A field of view across `length` of the film, as the horizontal one.
    let horizontal = |length: f32| ((fov.to_radians() / 2.0).tan() * w / length).atan().to_degrees() * 2.0;
    let (fov_degrees, fov_axis) = match axis {
        "x" => (fov, FovAxis::Horizontal),
        "y" => (fov, FovAxis::Vertical),
        "smaller" => (fov, FovAxis::Smaller),
        "larger" => (fov, if w >= h { FovAxis::Horizontal } else { FovAxis::Vertical }),
        "diagonal" => (horizontal(w.hypot(h)), FovAxis::Horizontal),
        _ => {
            return Err(ctx.error(
                node,
                format!("fov_axis '{axis}' is not x, y, diagonal, smaller or larger"),
            ));
        }
    };
    props.finish(ctx);
    Ok((
        Camera {
            position: m.transform_point3(Vec3::ZERO).to_array(),
            look: Look::Forward(m.transform_vector3(Vec3::Z).normalize().to_array()),
            up: m.transform_vector3(Vec3::Y).normalize().to_array(),
            fov_degrees,
            fov_axis,
            lens,
        },
        size,
    ))
}

/// A film's width and height (Mitsuba's defaults 768 x 576); a crop window is warned about.
fn film_size(ctx: &mut Context, film: Node) -> Result<(u32, u32)> {
    let props = Props::new(film);
    let width = props.integer(ctx, "width")?.unwrap_or(768);
    let height = props.integer(ctx, "height")?.unwrap_or(576);
    if !(1..=16384).contains(&width) || !(1..=16384).contains(&height) {
        return Err(ctx.error(
            film,
            format!("the film size {width}x{height} is not between 1 and 16384"),
        ));
    }
    props.finish(ctx);
    Ok((width as u32, height as u32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use roxmltree::Document;
    use std::path::Path;

    /// A converted sensor (camera and film size) and the warnings.
    type Converted = (Result<(Camera, (u32, u32))>, Vec<String>);

    fn convert(xml: &str) -> Converted {
        let doc = Document::parse(xml).unwrap();
        let mut ctx = Context::new("c.xml", Path::new("."), &doc).unwrap();
        (sensor(&mut ctx, doc.root_element()), ctx.warnings)
    }

    #[test]
    fn a_look_at_camera_keeps_its_view_and_film() {
        let (c, w) = convert(
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><string name=\"fovAxis\" value=\"y\"/>\
             <transform name=\"toWorld\"><lookat origin=\"0 1 5\" target=\"0 1 0\" up=\"0 1 0\"/></transform>\
             <film type=\"hdrfilm\"><integer name=\"width\" value=\"64\"/><integer name=\"height\" value=\"32\"/>\
             <rfilter type=\"gaussian\"/></film></sensor>",
        );
        assert!(w.is_empty(), "{w:?}");
        let (c, size) = c.unwrap();
        assert_eq!(size, (64, 32));
        assert_eq!(c.position, [0.0, 1.0, 5.0]);
        let Look::Forward(f) = c.look else { panic!() };
        assert!((Vec3::from(f) - Vec3::NEG_Z).length() < 1e-6);
        assert_eq!((c.fov_degrees, c.fov_axis), (40.0, FovAxis::Vertical));
    }

    #[test]
    fn thin_lenses_keep_their_aperture_and_focus() {
        let lens = |props: &str| {
            let (c, w) = convert(&format!(
                "<sensor type=\"thinlens\"><float name=\"fov\" value=\"40\"/>{props}</sensor>"
            ));
            (c.map(|(c, _)| c.lens), w)
        };
        let (l, w) =
            lens("<float name=\"aperture_radius\" value=\"0.1\"/><float name=\"focus_distance\" value=\"3\"/>");
        assert_eq!(
            l.unwrap(),
            Some(ThinLens {
                aperture_radius: 0.1,
                focus_distance: 3.0
            })
        );
        assert!(w.is_empty(), "{w:?}");
        // Mitsuba 3 focuses at the far clip distance by default; a radius of 0 is a pinhole.
        let (l, _) = lens("<float name=\"aperture_radius\" value=\"0.1\"/>");
        assert_eq!(l.unwrap().unwrap().focus_distance, 1e4);
        let (l, _) = lens("<float name=\"aperture_radius\" value=\"0\"/>");
        assert_eq!(l.unwrap(), None);
        let (l, _) = lens("<float name=\"focus_distance\" value=\"3\"/>");
        assert!(l.unwrap_err().message.contains("needs its aperture_radius"));
        let (l, _) =
            lens("<float name=\"aperture_radius\" value=\"0.1\"/><float name=\"focus_distance\" value=\"-1\"/>");
        assert!(l.unwrap_err().message.contains("is not a distance"));
    }

    #[test]
    fn diagonal_fields_of_view_become_horizontal_ones() {
        let (c, _) = convert(
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"90\"/><string name=\"fov_axis\" value=\"diagonal\"/>\
             <film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"3\"/></film></sensor>",
        );
        let (c, _) = c.unwrap();
        // tan(45°) * 4 / 5 = 0.8 across half the width.
        assert!((c.fov_degrees - 2.0 * 0.8f32.atan().to_degrees()).abs() < 1e-4);
        assert_eq!(c.fov_axis, FovAxis::Horizontal);
    }

    #[test]
    fn mirrors_and_bad_sensors_are_reported() {
        let (c, w) = convert(
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"30\"/><transform name=\"to_world\"><scale x=\"-1\"/></transform></sensor>",
        );
        assert!(c.is_ok());
        assert!(w[0].contains("mirrors"), "{w:?}");
        let (c, _) = convert("<sensor type=\"orthographic\"/>");
        assert!(c.unwrap_err().message.contains("only perspective"));
        let (c, _) = convert("<sensor type=\"perspective\"><float name=\"fov\" value=\"190\"/></sensor>");
        assert!(c.unwrap_err().message.contains("between 0 and 180"));
    }
}
