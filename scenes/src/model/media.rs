//! Participating media: homogeneous media with a phase function, the boundaries that enclose
//! them (a material's `interior` and `exterior`, `null` boundaries that rays cross without a
//! vertex) and the medium around the camera; heterogeneous media, whose density a grid gives
//! ([`super::grid`]); and the rules they must satisfy (docs/media.md).

use super::grid::{DensityGrid, VolumeGrid, invert_affine};
use super::{Material, Rgb, Scene};
use serde::Deserialize;
use std::sync::Arc;

/// A medium: absorption and scattering coefficients per unit length and channel (both times
/// `scale`), and the phase function of its scattering. With a density grid the medium is
/// heterogeneous: the coefficients are per unit density, times the grid's density.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Medium {
    /// Absorption coefficient σa per channel.
    #[serde(default)]
    pub sigma_a: Rgb,
    /// Scattering coefficient σs per channel.
    #[serde(default)]
    pub sigma_s: Rgb,
    /// A factor of both coefficients (Mitsuba's `scale`: the coefficients in other units).
    #[serde(default = "super::unit")]
    pub scale: f32,
    /// How scattered light leaves a point of the medium.
    #[serde(default)]
    pub phase: Phase,
    /// A density grid (heterogeneous medium); none: homogeneous.
    #[serde(default)]
    pub grid: Option<DensityGrid>,
}

impl Medium {
    /// The extinction coefficient σt = σa + σs per channel, scaled.
    pub fn sigma_t(&self) -> Rgb {
        std::array::from_fn(|c| (self.sigma_a[c] + self.sigma_s[c]) * self.scale)
    }

    /// The scattering coefficient, scaled.
    pub fn sigma_s_scaled(&self) -> Rgb {
        self.sigma_s.map(|s| s * self.scale)
    }
}

/// A phase function.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
pub enum Phase {
    /// Every direction alike (1 / 4π).
    #[default]
    Isotropic,
    /// Henyey and Greenstein's, of mean cosine `g` in (−1, 1): forward scattering for g > 0.
    HenyeyGreenstein {
        /// The mean cosine between the incoming and the outgoing direction of travel.
        g: f32,
    },
}

impl Phase {
    /// The mean cosine g (0 for isotropic scattering).
    pub fn g(&self) -> f32 {
        match self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => *g,
        }
    }
}

/// Checks one medium: finite, non-negative coefficients and scale, |g| < 1.
pub fn check_medium(m: &Medium) -> Result<(), String> {
    let bad = |v: &Rgb| v.iter().any(|c| !c.is_finite() || *c < 0.0);
    if bad(&m.sigma_a) {
        return Err(format!("sigma_a {:?} must be finite and not negative", m.sigma_a));
    }
    if bad(&m.sigma_s) {
        return Err(format!("sigma_s {:?} must be finite and not negative", m.sigma_s));
    }
    if !m.scale.is_finite() || m.scale < 0.0 {
        return Err(format!("scale {} must be finite and not negative", m.scale));
    }
    let g = m.phase.g();
    if g.is_nan() || g.abs() >= 1.0 {
        return Err(format!("the Henyey-Greenstein g {g} must lie in (-1, 1)"));
    }
    if let Some(grid) = &m.grid {
        check_grid(m, grid)?;
    }
    Ok(())
}

/// Checks a medium's grid: a grey extinction (delta tracking samples one distance for all
/// channels; the albedo may be coloured) and an invertible, finite map to the world.
fn check_grid(m: &Medium, grid: &DensityGrid) -> Result<(), String> {
    let t = m.sigma_t();
    if t.iter().any(|&c| (c - t[0]).abs() > 1e-5 * t[0].abs().max(1e-30)) {
        return Err(format!(
            "a density grid needs a grey extinction: sigma_a + sigma_s is {t:?} (the albedo may differ per channel)"
        ));
    }
    if grid.to_world.iter().flatten().any(|v| !v.is_finite()) || invert_affine(&grid.to_world).is_none() {
        return Err(format!(
            "the grid's to_world {:?} is not an invertible, finite map",
            grid.to_world
        ));
    }
    Ok(())
}

/// Reads the density grid of every medium that has one and has not read it, with `read`
/// (which takes the grid's `file` as the scene writes it). An error gives the medium's name
/// to locate and the message, naming the medium and the file.
pub fn load_grids(scene: &mut Scene, read: impl Fn(&str) -> Result<Vec<u8>, String>) -> Result<(), (String, String)> {
    for (name, m) in &mut scene.media {
        let Some(grid) = m.grid.as_mut().filter(|g| g.volume.is_none()) else {
            continue;
        };
        let volume = read(&grid.file)
            .and_then(|bytes| VolumeGrid::from_vol(&bytes))
            .map_err(|e| {
                (
                    format!("\"{name}\""),
                    format!("medium '{name}': grid '{}': {e}", grid.file),
                )
            })?;
        grid.volume = Some(Arc::new(volume));
    }
    Ok(())
}

/// Checks a material's media: names the scene defines, and a `null` boundary that scatters
/// and emits nothing.
pub fn check_material_media(m: &Material, scene: &Scene) -> Result<(), String> {
    for name in [&m.interior, &m.exterior].into_iter().flatten() {
        if !scene.media.contains_key(name) {
            return Err(unknown_medium(name, scene));
        }
    }
    if m.null
        && (m.pbr.is_some()
            || [m.diffuse, m.phong, m.mirror]
                .iter()
                .any(|c| c.iter().any(|&v| v != 0.0)))
    {
        return Err("a null (index-matched) boundary has no lobes: remove diffuse, phong, mirror and pbr".into());
    }
    Ok(())
}

/// The error for a medium name the scene does not define.
pub fn unknown_medium(name: &str, scene: &Scene) -> String {
    let known: Vec<&str> = scene.media.keys().map(String::as_str).collect();
    format!("unknown medium '{name}' (media: {})", known.join(", "))
}

/// Whether the scene has anything of media: a medium, a boundary or a null material.
pub fn uses_media(scene: &Scene) -> bool {
    !scene.media.is_empty()
        || scene
            .materials
            .values()
            .any(|m| m.null || m.interior.is_some() || m.exterior.is_some())
}

/// Checks every medium, every material's media and the camera's medium. An error gives the
/// name to locate (the medium's or material's, quoted as the file writes it) and the message.
pub fn check_media(scene: &Scene) -> Result<(), (String, String)> {
    for (name, m) in &scene.media {
        check_medium(m).map_err(|e| (format!("\"{name}\""), format!("medium '{name}': {e}")))?;
    }
    for (name, m) in &scene.materials {
        check_material_media(m, scene).map_err(|e| (format!("\"{name}\""), format!("material '{name}': {e}")))?;
    }
    if let Some(name) = &scene.camera_medium
        && !scene.media.contains_key(name)
    {
        return Err((
            "camera_medium".into(),
            format!("camera_medium: {}", unknown_medium(name, scene)),
        ));
    }
    Ok(())
}
