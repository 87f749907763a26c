//! Each light's estimated power, which sets how often the light is picked.

use crate::gpu::{GpuLight, light_kind};
use crate::model::luminance;

/// A light's estimated power: the luminance of the flux it emits. Area: π A L (one side);
/// point: 4π I; spot: I × its cone's integral of the falloff, 2π ((1 − cos inner) +
/// (cos inner − cos outer) / 3) for glTF's, 2π (1 − (sin θo − sin θi) / (θo − θi)) for
/// Mitsuba's linear one; directional: E π r² through a disk of the scene's bounding
/// radius `radius`; background and environment: the flux π L̄ × π r² they send onto one side of
/// that disk, with L̄ the mean luminance over the sphere (`mean_env_luminance` × scale for a
/// map). Only ratios matter: they set how often each light is picked.
pub fn light_power(l: &GpuLight, radius: f64, mean_env_luminance: f64) -> f64 {
    use std::f64::consts::PI;
    let lum = luminance(l.radiance);
    let disk = PI * radius * radius;
    match l.kind {
        light_kind::AREA if l.inv_area > 0.0 => PI * lum / l.inv_area as f64,
        light_kind::AREA => 0.0,
        light_kind::POINT => 4.0 * PI * lum,
        light_kind::SPOT if l.e2[0] != 0.0 => {
            // Linear in the angle: 1 - (sin θo - sin θi) / (θo - θi) over the solid angle 2π.
            let (ti, to) = ((l.cos_inner as f64).acos(), (l.cos_outer as f64).acos());
            let ramp = if to > ti {
                (to.sin() - ti.sin()) / (to - ti)
            } else {
                ti.cos()
            };
            2.0 * PI * lum * (1.0 - ramp)
        }
        light_kind::SPOT => {
            let (ci, co) = (l.cos_inner as f64, l.cos_outer as f64);
            2.0 * PI * lum * ((1.0 - ci) + (ci - co).max(0.0) / 3.0)
        }
        light_kind::DIRECTIONAL => lum * disk,
        light_kind::BACKGROUND => PI * lum * disk,
        _ => PI * lum * mean_env_luminance * disk,
    }
}
