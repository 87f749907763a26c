//! Environment maps: equirectangular images (`.hdr` through the `image` crate's Radiance
//! decoder, `.exr` through the `exr` crate) and the 2D piecewise-constant distribution that
//! importance-samples them on the GPU.
//!
//! Convention (map space, before the light's rotation about +Y): row 0 is the top, +Y; the
//! angle from +Y is θ = π v and the azimuth φ = 2π (u − 1/2), so that
//! direction(u, v) = (sin θ sin φ, cos θ, −sin θ cos φ): the image's centre column (u = 1/2)
//! looks along −Z, u = 3/4 along +X, and u = 0 and 1 along +Z. Radiance is looked up in the
//! texel containing (u, v) (no filtering). A texel is sampled with probability proportional
//! to its luminance × solid angle, uniformly in (u, v) within it: the solid-angle density is
//! pdf(u, v) / (2π² sin θ), proportional to luminance × sin θ_centre / sin θ.

use crate::alias::luminance;
use std::f64::consts::PI;
use std::path::Path;

/// An equirectangular map of linear RGB radiance, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentMap {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Radiance per texel.
    pub texels: Vec<[f32; 3]>,
}

/// The map as the GPU samples it.
#[derive(Debug, Clone)]
pub struct Distribution {
    /// Radiance (RGB) and, in the fourth component, the density over [0, 1]² of sampling
    /// (u, v) in the texel: proportional to luminance × sin θ at the row's centre.
    pub texels: Vec<[f32; 4]>,
    /// Each row's conditional CDF over its columns (`width + 1` values from 0 to 1), then the
    /// marginal CDF over the rows (`height + 1` values).
    pub cdf: Vec<f32>,
    /// Mean luminance over the sphere (solid-angle weighted).
    pub mean_luminance: f64,
}

impl EnvironmentMap {
    /// Reads `.hdr` or `.exr` (by extension); errors name the file.
    pub fn load(path: &Path) -> Result<EnvironmentMap, String> {
        let shown = path.display();
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let map = match extension.as_str() {
            "hdr" => read_hdr(path),
            "exr" => read_exr(path),
            _ => Err("an environment map must be a Radiance .hdr or OpenEXR .exr image".to_string()),
        };
        map.and_then(|(width, height, texels)| EnvironmentMap::new(width, height, texels))
            .map_err(|e| format!("{shown}: {e}"))
    }

    /// A map of `width` × `height` texels; radiance must be finite and non-negative.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Result<EnvironmentMap, String> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(format!(
                "{} texels do not make a {width} x {height} image",
                texels.len()
            ));
        }
        if let Some(i) = texels.iter().position(|t| t.iter().any(|c| !c.is_finite() || *c < 0.0)) {
            return Err(format!(
                "texel ({}, {}) is {:?}: radiance must be finite and non-negative",
                i % width as usize,
                i / width as usize,
                texels[i]
            ));
        }
        Ok(EnvironmentMap { width, height, texels })
    }

    /// The sampling distribution: texel (i, j) is picked with probability proportional to
    /// its luminance × sin θ at its row's centre, which is proportional to luminance × the
    /// texel's solid angle (a row's solid angle is sin θ_centre × 2 sin(Δθ/2) × Δφ, and
    /// 2 sin(Δθ/2) is the same for every row). A black map is sampled uniformly.
    pub fn distribution(&self) -> Distribution {
        let (w, h) = (self.width as usize, self.height as usize);
        let sin_row: Vec<f64> = (0..h).map(|i| (PI * (i as f64 + 0.5) / h as f64).sin()).collect();
        let mut f: Vec<f64> = (0..w * h).map(|k| luminance(self.texels[k]) * sin_row[k / w]).collect();
        if f.iter().sum::<f64>() <= 0.0 {
            f = (0..w * h).map(|k| sin_row[k / w]).collect();
        }
        let integral = f.iter().sum::<f64>() / (w * h) as f64;
        let texels = self
            .texels
            .iter()
            .zip(&f)
            .map(|(t, f)| [t[0], t[1], t[2], (f / integral) as f32])
            .collect();
        let mut cdf = Vec::with_capacity(h * (w + 1) + h + 1);
        let mut rows = Vec::with_capacity(h);
        for row in f.chunks_exact(w) {
            let sum: f64 = row.iter().sum();
            rows.push(sum);
            push_cdf(&mut cdf, row, sum);
        }
        push_cdf(&mut cdf, &rows, rows.iter().sum());
        let mean_luminance = (0..w * h)
            .map(|k| luminance(self.texels[k]) * texel_solid_angle(k / w, w, h))
            .sum::<f64>()
            / (4.0 * PI);
        Distribution {
            texels,
            cdf,
            mean_luminance,
        }
    }
}

/// The CDF of `values` (summing to `sum`; uniform when 0): `values.len() + 1` entries, the
/// first exactly 0 and the last exactly 1.
fn push_cdf(out: &mut Vec<f32>, values: &[f64], sum: f64) {
    let n = values.len();
    let mut running = 0.0;
    out.push(0.0);
    for (k, v) in values.iter().enumerate() {
        running += v;
        out.push(if k + 1 == n {
            1.0
        } else if sum > 0.0 {
            (running / sum) as f32
        } else {
            (k + 1) as f32 / n as f32
        });
    }
}

/// The solid angle of a texel in row `row` of a `width` × `height` map.
pub fn texel_solid_angle(row: usize, width: usize, height: usize) -> f64 {
    let theta = |i: usize| PI * i as f64 / height as f64;
    2.0 * PI / width as f64 * (theta(row).cos() - theta(row + 1).cos())
}

/// The map-space direction of image coordinates (u, v) in [0, 1]² (see the module's
/// convention).
pub fn direction(u: f64, v: f64) -> [f64; 3] {
    let (theta, phi) = (PI * v, 2.0 * PI * (u - 0.5));
    [theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()]
}

/// The image coordinates (u, v) of a unit map-space direction, the inverse of [`direction`].
pub fn uv(d: [f64; 3]) -> (f64, f64) {
    let phi = d[0].atan2(-d[2]);
    (0.5 + phi / (2.0 * PI), d[1].clamp(-1.0, 1.0).acos() / PI)
}

fn read_hdr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let image = image::ImageReader::with_format(std::io::BufReader::new(file), image::ImageFormat::Hdr)
        .decode()
        .map_err(|e| e.to_string())?
        .into_rgb32f();
    let (width, height) = image.dimensions();
    let texels = image.pixels().map(|p| p.0).collect();
    Ok((width, height, texels))
}

fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |size: Vec2<usize>, _| (size.width(), vec![[0f32; 3]; size.width() * size.height()]),
        |(width, texels): &mut (usize, Vec<[f32; 3]>), at: Vec2<usize>, (r, g, b, _): (f32, f32, f32, f32)| {
            texels[at.y() * *width + at.x()] = [r, g, b];
        },
    )
    .map_err(|e| e.to_string())?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    Ok((size.width() as u32, size.height() as u32, texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_and_uv_are_inverse_and_follow_the_convention() {
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(close(direction(0.5, 0.5), [0.0, 0.0, -1.0]), "centre: -Z");
        assert!(close(direction(0.75, 0.5), [1.0, 0.0, 0.0]), "u = 3/4: +X");
        assert!(close(direction(0.0, 0.5), [0.0, 0.0, 1.0]), "u = 0: +Z");
        assert!(close(direction(0.3, 0.0), [0.0, 1.0, 0.0]), "top row: +Y");
        for (u, v) in [(0.1, 0.2), (0.6, 0.9), (0.99, 0.5), (0.25, 0.75)] {
            let (u2, v2) = uv(direction(u, v));
            assert!(
                (u - u2).abs() < 1e-12 && (v - v2).abs() < 1e-12,
                "({u}, {v}) -> ({u2}, {v2})"
            );
        }
    }

    #[test]
    fn the_distribution_is_normalised_and_proportional_to_luminance_times_solid_angle() {
        let texels: Vec<[f32; 3]> = (0..24).map(|k| [k as f32, 0.5, (k % 5) as f32]).collect();
        let map = EnvironmentMap::new(6, 4, texels).unwrap();
        let d = map.distribution();
        let (w, h) = (6, 4);
        assert_eq!(d.cdf.len(), h * (w + 1) + h + 1);
        // The probability of each texel from the CDFs, against luminance × solid angle.
        let marginal = &d.cdf[h * (w + 1)..];
        let total: f64 = (0..w * h)
            .map(|k| luminance(map.texels[k]) * texel_solid_angle(k / w, w, h))
            .sum();
        for k in 0..w * h {
            let (i, j) = (k / w, k % w);
            let row = &d.cdf[i * (w + 1)..];
            let p = (marginal[i + 1] - marginal[i]) as f64 * (row[j + 1] - row[j]) as f64;
            let expected = luminance(map.texels[k]) * texel_solid_angle(i, w, h) / total;
            assert!((p - expected).abs() < 1e-6, "texel {k}: {p} vs {expected}");
            // The density over [0, 1]² is the probability times the texel count.
            assert!((d.texels[k][3] as f64 - p * (w * h) as f64).abs() < 1e-5 * (w * h) as f64);
        }
        assert!((d.mean_luminance - total / (4.0 * PI)).abs() < 1e-12);
    }

    #[test]
    fn bad_maps_are_refused() {
        assert!(
            EnvironmentMap::new(2, 2, vec![[1.0; 3]; 3])
                .unwrap_err()
                .contains("2 x 2")
        );
        let e = EnvironmentMap::new(2, 1, vec![[1.0; 3], [f32::NAN, 0.0, 0.0]]).unwrap_err();
        assert!(e.contains("texel (1, 0)"), "{e}");
        let e = EnvironmentMap::load(Path::new("sky.png")).unwrap_err();
        assert!(e.starts_with("sky.png: ") && e.contains(".hdr"), "{e}");
    }

    #[test]
    fn an_exr_map_round_trips() {
        let path = std::env::temp_dir().join(format!("lightgraph-env-{}.exr", std::process::id()));
        exr::prelude::write_rgb_file(&path, 4, 2, |x, y| (x as f32, y as f32, 0.25)).unwrap();
        let map = EnvironmentMap::load(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!((map.width, map.height), (4, 2));
        assert_eq!(map.texels[6], [2.0, 1.0, 0.25]);
    }
}
