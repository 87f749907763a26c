//! The rules a scene must satisfy wherever it comes from (a RON file, a glTF asset, a Mitsuba
//! file): a field of view in (0, 180) degrees, at most one environment light and spot cones
//! within 0 to 90 degrees, and, once its imports are resolved, geometry, light and sound media
//! enclosed by closed surfaces ([`super::enclosure`]).

use super::{Light, Scene, Shape};

pub(crate) fn check_fov(fov_degrees: f32) -> Result<(), String> {
    if fov_degrees > 0.0 && fov_degrees < 180.0 {
        Ok(())
    } else {
        Err(format!("field of view {fov_degrees} is not in (0, 180) degrees"))
    }
}

/// Checks the lights of a scene: at most one Background or Environment, spot cones within
/// 0 ≤ inner ≤ outer ≤ 90 degrees. Errors give a word to locate and the message.
pub(crate) fn check_lights(lights: &[Light]) -> Result<(), (&'static str, String)> {
    let environments = lights
        .iter()
        .filter(|l| matches!(l, Light::Background { .. } | Light::Environment { .. }))
        .count();
    if environments > 1 {
        return Err((
            "Environment",
            format!("a scene has at most one Background or Environment light; this one has {environments}"),
        ));
    }
    for light in lights {
        if let Light::Spot {
            inner_cone_degrees: inner,
            outer_cone_degrees: outer,
            ..
        } = light
            && !(0.0 <= *inner && inner <= outer && *outer <= 90.0)
        {
            return Err((
                "Spot",
                format!(
                    "spot light cone angles inner {inner} and outer {outer} degrees must satisfy 0 <= inner <= outer <= 90"
                ),
            ));
        }
    }
    Ok(())
}

/// Checks that a scene with its imports resolved has geometry and light, and sound media, each
/// enclosed by closed surfaces.
pub(crate) fn check_resolved(scene: &Scene) -> Result<(), String> {
    if scene.shapes.is_empty() {
        return Err("the scene is empty: it has no shapes".into());
    }
    let emissive = scene.shapes.iter().any(Shape::emits);
    if !emissive && scene.lights.is_empty() {
        return Err("the scene has no light: add an emissive shape or a light (Point, Directional, Background)".into());
    }
    super::media::check_media(scene).map_err(|(_, message)| message)?;
    super::enclosure::check_enclosures(scene).map_err(|(_, message)| message)
}
