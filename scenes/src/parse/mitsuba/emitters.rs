//! Emitters: `area` (the radiance of its shape's triangles, one-sided along their normals,
//! as in Mitsuba) and the lights of the scene model: `point`, `spot`, `directional`,
//! `constant` and `envmap`. Every emitter's `scale` multiplies its value.

use super::transform::to_world;
use super::xml::{Color, Context, Props, Result};
use crate::model::environment::{EnvironmentMap, TexelLayout};
use crate::model::{Light, Rgb, SpotFalloff};
use glam::{Mat4, Vec3};
use roxmltree::Node;

/// A colour property of an emitter (`default` when absent) times its `scale`; a texture is
/// unsupported (warned about, and `default` used).
fn value<'a, 'i>(ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>, name: &str, default: Rgb) -> Result<Rgb> {
    let c = match props.color(ctx, name)? {
        Some(Color::Rgb(c)) => c,
        None => default,
        Some(Color::Texture(t)) => {
            ctx.warn(t, format!("a textured {name} is not supported: {default:?} is used"));
            default
        }
    };
    let scale = props.float(ctx, "scale")?.unwrap_or(1.0);
    let v = c.map(|c| c * scale);
    if v.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
        return Err(ctx.error(props.node(), format!("{name} {v:?} is not finite and non-negative")));
    }
    Ok(v)
}

/// The radiance of an `area` emitter nested in a shape.
pub fn area<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Option<Rgb>> {
    let kind = ctx.plugin_type(node)?;
    if kind != "area" {
        ctx.warn(
            node,
            "only area emitters can be attached to shapes: this one is ignored",
        );
        return Ok(None);
    }
    let props = Props::new(node);
    let radiance = value(ctx, &props, "radiance", [1.0; 3])?;
    props.finish(ctx);
    Ok(Some(radiance))
}

/// The light of a top-level emitter; `None` (with a warning) for an unsupported one.
pub fn light<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Option<Light>> {
    let kind = ctx.plugin_type(node)?;
    let props = Props::new(node);
    let light = match kind.as_str() {
        "point" => {
            let m = to_world(ctx, &props)?;
            let position = match props.point(ctx, "position")? {
                Some(p) => Vec3::from(p),
                None => m.transform_point3(Vec3::ZERO),
            };
            Light::Point {
                position: position.to_array(),
                intensity: value(ctx, &props, "intensity", [1.0; 3])?,
            }
        }
        "spot" => {
            let m = to_world(ctx, &props)?;
            let cutoff = props.float(ctx, "cutoff_angle")?.unwrap_or(20.0);
            let beam = props.float(ctx, "beam_width")?.unwrap_or(cutoff * 0.75);
            if !(0.0 <= beam && beam <= cutoff && cutoff <= 90.0) {
                return Err(ctx.error(
                    node,
                    format!(
                        "beam_width {beam} and cutoff_angle {cutoff} must satisfy 0 <= beam_width <= cutoff_angle <= 90"
                    ),
                ));
            }
            if props.get("texture").is_some() {
                ctx.warn(node, "a projected texture is not supported");
            }
            Light::Spot {
                position: m.transform_point3(Vec3::ZERO).to_array(),
                direction: direction(ctx, node, m)?,
                intensity: value(ctx, &props, "intensity", [1.0; 3])?,
                inner_cone_degrees: beam,
                outer_cone_degrees: cutoff,
                falloff: SpotFalloff::Linear,
            }
        }
        "directional" => {
            let m = to_world(ctx, &props)?;
            let d = match props.point(ctx, "direction")? {
                Some(d) => Vec3::from(d).normalize_or_zero(),
                None => direction(ctx, node, m)?.into(),
            };
            if d == Vec3::ZERO {
                return Err(ctx.error(node, "the direction is zero"));
            }
            Light::Directional {
                direction: d.to_array(),
                irradiance: value(ctx, &props, "irradiance", [1.0; 3])?,
            }
        }
        "constant" => Light::Background {
            radiance: value(ctx, &props, "radiance", [1.0; 3])?,
            scale: 1.0,
        },
        "envmap" => envmap(ctx, &props)?,
        _ => {
            ctx.warn(node, "unsupported emitter: it gives no light");
            return Ok(None);
        }
    };
    props.finish(ctx);
    Ok(Some(light))
}

/// The direction local +Z takes (where Mitsuba's spot and directional emitters shine).
fn direction(ctx: &Context, node: Node, m: Mat4) -> Result<[f32; 3]> {
    let d = m.transform_vector3(Vec3::Z).normalize_or_zero();
    if d == Vec3::ZERO {
        return Err(ctx.error(node, "to_world maps +Z to zero"));
    }
    Ok(d.to_array())
}

/// An `envmap`: Mitsuba's equirectangular map is lightgraph's turned by 180 degrees about
/// +Y (its u = 0 looks along -Z, lightgraph's along +Z), plus to_world's rotation about +Y
/// (other rotations are unsupported); its rows span pole to pole ([`TexelLayout::PoleToPole`]).
fn envmap(ctx: &mut Context, props: &Props) -> Result<Light> {
    let node = props.node();
    let path = props.file(ctx, "an envmap")?;
    let scale = props.float(ctx, "scale")?.unwrap_or(1.0);
    let m = to_world(ctx, props)?;
    let x = m.transform_vector3(Vec3::X).normalize_or_zero();
    let y = m.transform_vector3(Vec3::Y).normalize_or_zero();
    if (y - Vec3::Y).length() > 1e-3 {
        ctx.warn(
            node,
            "to_world turns +Y: only rotations about +Y are supported, the map is upright",
        );
    }
    // to_world turns +X by beta about +Y: x = (cos beta, 0, -sin beta).
    let beta = (-x.z).atan2(x.x).to_degrees();
    let map = EnvironmentMap::load(&path).map_err(|e| ctx.error(node, e))?;
    Ok(Light::Environment {
        file: path.display().to_string(),
        scale,
        rotation_degrees: beta + 180.0,
        layout: TexelLayout::PoleToPole,
        map: Some(std::sync::Arc::new(map)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use roxmltree::Document;
    use std::path::Path;

    fn convert(xml: &str) -> (Result<Option<Light>>, Vec<String>) {
        let doc = Document::parse(xml).unwrap();
        let mut ctx = Context::new("e.xml", Path::new("."), &doc).unwrap();
        (light(&mut ctx, doc.root_element()), ctx.warnings)
    }

    #[test]
    fn point_spot_directional_and_constant_emitters_become_lights() {
        let (l, w) = convert(
            "<emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/><rgb name=\"intensity\" value=\"5\"/><float name=\"scale\" value=\"2\"/></emitter>",
        );
        assert!(w.is_empty(), "{w:?}");
        let Some(Light::Point { position, intensity }) = l.unwrap() else {
            panic!()
        };
        assert_eq!((position, intensity), ([1.0, 2.0, 3.0], [10.0; 3]));
        let (l, w) = convert(
            "<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0 5 0\" target=\"0 0 0\" up=\"0 0 1\"/></transform><float name=\"cutoff_angle\" value=\"30\"/></emitter>",
        );
        let Some(Light::Spot {
            position,
            direction,
            inner_cone_degrees,
            outer_cone_degrees,
            falloff,
            ..
        }) = l.unwrap()
        else {
            panic!()
        };
        assert_eq!(
            (position, inner_cone_degrees, outer_cone_degrees, falloff),
            ([0.0, 5.0, 0.0], 22.5, 30.0, SpotFalloff::Linear)
        );
        assert!((Vec3::from(direction) - Vec3::NEG_Y).length() < 1e-6);
        assert!(w.is_empty(), "Mitsuba's falloff is exact: {w:?}");
        let (l, _) = convert("<emitter type=\"directional\"><vector name=\"direction\" value=\"0, -2, 0\"/></emitter>");
        let Some(Light::Directional { direction, irradiance }) = l.unwrap() else {
            panic!()
        };
        assert_eq!((direction, irradiance), ([0.0, -1.0, 0.0], [1.0; 3]));
        let (l, _) = convert("<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5\"/></emitter>");
        assert!(matches!(
            l.unwrap(),
            Some(Light::Background {
                radiance: [0.5, 0.5, 0.5],
                ..
            })
        ));
    }

    #[test]
    fn an_envmap_is_filtered_with_its_rows_from_pole_to_pole() {
        let path = std::env::temp_dir().join(format!("lightgraph-envmap-{}.exr", std::process::id()));
        exr::prelude::write_rgb_file(&path, 4, 3, |x, y| (x as f32, y as f32, 1.0)).unwrap();
        let (l, w) = convert(&format!(
            "<emitter type=\"envmap\"><string name=\"filename\" value=\"{}\"/><float name=\"scale\" value=\"2\"/></emitter>",
            path.display()
        ));
        std::fs::remove_file(&path).unwrap();
        assert!(w.is_empty(), "{w:?}");
        let Some(Light::Environment {
            scale,
            rotation_degrees,
            layout,
            map,
            ..
        }) = l.unwrap()
        else {
            panic!()
        };
        assert_eq!((scale, rotation_degrees, layout), (2.0, 180.0, TexelLayout::PoleToPole));
        assert_eq!(map.map(|m| (m.width, m.height)), Some((4, 3)));
    }

    #[test]
    fn unsupported_emitters_warn_and_bad_ones_are_errors() {
        let (l, w) = convert("<emitter type=\"sunsky\"/>");
        assert!(l.unwrap().is_none());
        assert_eq!(
            w,
            ["e.xml:1:1: <emitter type=\"sunsky\">: unsupported emitter: it gives no light"]
        );
        let (l, _) = convert("<emitter type=\"point\">\n  <rgb name=\"intensity\" value=\"-1\"/></emitter>");
        assert!(l.unwrap_err().message.contains("not finite and non-negative"));
        let (l, _) = convert("<emitter type=\"envmap\"><string name=\"filename\" value=\"nowhere.exr\"/></emitter>");
        assert!(l.unwrap_err().message.contains("does not exist"));
    }
}
