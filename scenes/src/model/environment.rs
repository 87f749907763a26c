//! Environment maps: equirectangular images (`.hdr` through the `image` crate's Radiance
//! decoder, `.exr` through the `exr` crate), filtered bilinearly, and the distribution that
//! importance-samples the filtered map on the GPU.
//!
//! Convention (map space, before the light's rotation about +Y): row 0 is the top, +Y; the
//! angle from +Y is θ = π v and the azimuth φ = 2π (u − 1/2), so that
//! direction(u, v) = (sin θ sin φ, cos θ, −sin θ cos φ): the image's centre column (u = 1/2)
//! looks along −Z, u = 3/4 along +X, and u = 0 and 1 along +Z.
//!
//! Filtering: each texel's value sits at one point of [0, 1]², and the radiance between the
//! points is interpolated bilinearly, wrapping in u. Texel (i, j) of a w × h map sits at
//! u = (i + 1/2) / w, and, by the [`TexelLayout`], at v = (j + 1/2) / h (`Centred`:
//! lightgraph's scenes, glTF; v is clamped to the first and last rows' centres) or at
//! v = j / (h − 1) (`PoleToPole`: Mitsuba 3's `envmap`, whose rows span pole to pole).
//!
//! Sampling: the cells between neighbouring texel positions are bilinear patches ([`Patches`]).
//! A patch is picked with probability proportional to the mean of its corners' luminances
//! times its solid angle (a marginal CDF over the patch rows, a conditional CDF per row), and a
//! point in it with density proportional to the bilinear interpolation of those luminances.
//! The density over [0, 1]² is therefore a constant per patch row (stored after the CDFs,
//! [`Distribution::cdf`]) times the filtered luminance, nonzero wherever the filtered radiance
//! is, and the solid-angle density is that over 2π² sin θ. The GPU's `env_sample` and
//! `env_lookup` (shaders/lib/environment.wgsl) compute it by the same steps as
//! [`Distribution::sample`] and [`Distribution::pdf`].

use crate::model::luminance;
use serde::Deserialize;
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

/// Where in [0, 1]² a map's texel values sit (u always at the texel's centre, (i + 1/2) / w).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum TexelLayout {
    /// Row j at its centre, v = (j + 1/2) / h; above the first and below the last centre the
    /// radiance is that of the first and last row.
    #[default]
    Centred,
    /// Row j at v = j / (h − 1): the first row at the +Y pole, the last at −Y (Mitsuba 3).
    PoleToPole,
}

/// The bilinear patches of a `width` × `height` map: patch (row r, column k) lies between
/// texel columns k and k + 1 (mod width), u from (k + 1/2) / w to (k + 3/2) / w (mod 1), and
/// between the texel rows [`Patches::texel_rows`] gives, v from [`Patches::edge`] `(r)` to
/// `edge(r + 1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patches {
    /// Texels per row.
    pub width: u32,
    /// Rows of texels.
    pub height: u32,
    /// Where the texels sit.
    pub layout: TexelLayout,
}

/// A point of a map in its patch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchPoint {
    /// The patch row.
    pub row: usize,
    /// The patch column.
    pub col: usize,
    /// The position in the patch, [0, 1]² (s along u, t along v).
    pub st: [f64; 2],
}

impl Patches {
    /// The number of patch rows: `height + 1` when centred (the two outer ones half a row
    /// high, clamped to the first and last rows), `height − 1` from pole to pole (1 for a
    /// single row).
    pub fn rows(&self) -> usize {
        let h = self.height as usize;
        match self.layout {
            TexelLayout::Centred => h + 1,
            TexelLayout::PoleToPole => h.max(2) - 1,
        }
    }

    /// The v of patch row `r`'s top edge (`r` up to [`Patches::rows`]).
    pub fn edge(&self, r: usize) -> f64 {
        match self.layout {
            TexelLayout::Centred => ((r as f64 - 0.5) / self.height as f64).clamp(0.0, 1.0),
            TexelLayout::PoleToPole => r as f64 / self.rows() as f64,
        }
    }

    /// The texel rows at patch row `r`'s top and bottom edges.
    pub fn texel_rows(&self, r: usize) -> (usize, usize) {
        let last = self.height as usize - 1;
        match self.layout {
            TexelLayout::Centred => ((r.max(1) - 1).min(last), r.min(last)),
            TexelLayout::PoleToPole => (r.min(last), (r + 1).min(last)),
        }
    }

    /// The texel indices at a patch's corners: (k, top), (k + 1, top), (k, bottom),
    /// (k + 1, bottom).
    pub fn corners(&self, row: usize, col: usize) -> [usize; 4] {
        let w = self.width as usize;
        let (top, bottom) = self.texel_rows(row);
        let next = (col + 1) % w;
        [top * w + col, top * w + next, bottom * w + col, bottom * w + next]
    }

    /// The patch holding image coordinates (u, v) in [0, 1]², and the position in it.
    pub fn locate(&self, u: f64, v: f64) -> PatchPoint {
        let w = self.width as f64;
        let x = (u - 0.5 / w).rem_euclid(1.0) * w;
        let col = (x as usize).min(self.width as usize - 1);
        let rows = self.rows();
        let y = match self.layout {
            TexelLayout::Centred => v * self.height as f64 + 0.5,
            TexelLayout::PoleToPole => v * rows as f64,
        };
        let row = (y.max(0.0) as usize).min(rows - 1);
        let (v0, v1) = (self.edge(row), self.edge(row + 1));
        let t = ((v - v0) / (v1 - v0)).clamp(0.0, 1.0);
        PatchPoint {
            row,
            col,
            st: [(x - col as f64).clamp(0.0, 1.0), t],
        }
    }

    /// The image coordinates of a point in a patch, the inverse of [`Patches::locate`].
    pub fn uv(&self, p: &PatchPoint) -> (f64, f64) {
        let u = ((p.col as f64 + p.st[0] + 0.5) / self.width as f64).rem_euclid(1.0);
        let (v0, v1) = (self.edge(p.row), self.edge(p.row + 1));
        (u, v0 + (v1 - v0) * p.st[1])
    }
}

/// The bilinear interpolation of corner values (ordered as [`Patches::corners`]) at `st`.
pub fn bilerp(c: [f64; 4], st: [f64; 2]) -> f64 {
    let top = c[0] + (c[1] - c[0]) * st[0];
    let bottom = c[2] + (c[3] - c[2]) * st[0];
    top + (bottom - top) * st[1]
}

/// The map as the GPU samples it.
#[derive(Debug, Clone)]
pub struct Distribution {
    /// The patches sampled.
    pub patches: Patches,
    /// Radiance (RGB) and, in the fourth component, the sampling weight: the luminance, or 1
    /// everywhere for a black map (sampled uniformly).
    pub texels: Vec<[f32; 4]>,
    /// Each patch row's conditional CDF over its columns (`width + 1` values from 0 to 1),
    /// then the marginal CDF over the patch rows (`rows + 1` values), then each patch row's
    /// density: the density over [0, 1]² of sampling a point of the row is that times the
    /// bilinearly filtered sampling weight there.
    pub cdf: Vec<f32>,
    /// Mean luminance over the sphere (solid-angle weighted; each patch counted as the mean of
    /// its corners).
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

    /// The map's patches in `layout`.
    pub fn patches(&self, layout: TexelLayout) -> Patches {
        Patches {
            width: self.width,
            height: self.height,
            layout,
        }
    }

    /// The filtered radiance at image coordinates (u, v) with the texels in `layout` (the
    /// GPU's lookup, in double precision).
    pub fn radiance(&self, layout: TexelLayout, u: f64, v: f64) -> [f64; 3] {
        let patches = self.patches(layout);
        let p = patches.locate(u, v);
        let corners = patches.corners(p.row, p.col);
        std::array::from_fn(|c| bilerp(corners.map(|k| self.texels[k][c] as f64), p.st))
    }

    /// The sampling distribution of the map filtered with the texels in `layout`: patch
    /// (r, k) is picked with probability proportional to the mean of its corners' sampling
    /// weights times its solid angle, (2π / w)(cos θ_top − cos θ_bottom).
    pub fn distribution(&self, layout: TexelLayout) -> Distribution {
        let patches = self.patches(layout);
        let (w, rows) = (self.width as usize, patches.rows());
        let lum: Vec<f64> = self.texels.iter().map(|t| luminance(*t)).collect();
        let black = lum.iter().all(|l| *l <= 0.0);
        let weight: Vec<f64> = if black { vec![1.0; lum.len()] } else { lum };
        let band = |r: usize| (PI * patches.edge(r)).cos() - (PI * patches.edge(r + 1)).cos();
        // Each patch's mean weight times its solid angle.
        let mass: Vec<f64> = (0..rows * w)
            .map(|i| {
                let (r, k) = (i / w, i % w);
                let mean = patches.corners(r, k).iter().map(|&c| weight[c]).sum::<f64>() / 4.0;
                mean * 2.0 * PI / w as f64 * band(r)
            })
            .collect();
        let total: f64 = mass.iter().sum();
        let mut cdf = Vec::with_capacity(rows * (w + 1) + 2 * rows + 1);
        let mut row_mass = Vec::with_capacity(rows);
        for row in mass.chunks_exact(w) {
            let sum: f64 = row.iter().sum();
            row_mass.push(sum);
            push_cdf(&mut cdf, row, sum);
        }
        push_cdf(&mut cdf, &row_mass, row_mass.iter().sum());
        // Patch (r, k)'s probability mass / mean / (Δu Δv) = 2π band / (total Δv).
        cdf.extend((0..rows).map(|r| (2.0 * PI * band(r) / (total * (patches.edge(r + 1) - patches.edge(r)))) as f32));
        let texels = self
            .texels
            .iter()
            .zip(&weight)
            .map(|(t, w)| [t[0], t[1], t[2], *w as f32])
            .collect();
        Distribution {
            patches,
            texels,
            cdf,
            mean_luminance: if black { 0.0 } else { total / (4.0 * PI) },
        }
    }
}

impl Distribution {
    /// The marginal CDF over the patch rows.
    fn marginal(&self) -> &[f32] {
        let (w, rows) = (self.patches.width as usize, self.patches.rows());
        &self.cdf[rows * (w + 1)..rows * (w + 1) + rows + 1]
    }

    /// Patch row `r`'s conditional CDF over its columns.
    fn conditional(&self, r: usize) -> &[f32] {
        let w = self.patches.width as usize;
        &self.cdf[r * (w + 1)..(r + 1) * (w + 1)]
    }

    /// Patch row `r`'s density factor (see [`Distribution::cdf`]).
    fn row_density(&self, r: usize) -> f64 {
        let (w, rows) = (self.patches.width as usize, self.patches.rows());
        self.cdf[rows * (w + 1) + rows + 1 + r] as f64
    }

    /// The sampling weights at a patch's corners.
    fn corner_weights(&self, row: usize, col: usize) -> [f64; 4] {
        self.patches.corners(row, col).map(|k| self.texels[k][3] as f64)
    }

    /// The density over [0, 1]² with which [`Distribution::sample`] (and the GPU's
    /// `env_sample`) picks image coordinates (u, v); the solid-angle density is this over
    /// 2π² sin(π v).
    pub fn pdf(&self, u: f64, v: f64) -> f64 {
        let p = self.patches.locate(u, v);
        self.row_density(p.row) * bilerp(self.corner_weights(p.row, p.col), p.st)
    }

    /// Image coordinates (u, v) for uniform numbers `xi` in [0, 1)², as the GPU's
    /// `env_sample` draws them: a patch row from the marginal CDF (`xi[1]`), a column from the
    /// row's CDF (`xi[0]`), then the point from the patch's bilinear density, with the two
    /// numbers' positions within the CDFs' steps.
    pub fn sample(&self, xi: [f64; 2]) -> (f64, f64) {
        let (row, fy) = sample_cdf(self.marginal(), xi[1]);
        let (col, fx) = sample_cdf(self.conditional(row), xi[0]);
        let c = self.corner_weights(row, col);
        let t = sample_linear(c[0] + c[1], c[2] + c[3], fy);
        let s = sample_linear(c[0] + (c[2] - c[0]) * t, c[1] + (c[3] - c[1]) * t, fx);
        self.patches.uv(&PatchPoint { row, col, st: [s, t] })
    }
}

/// The step of `cdf` (from 0 to 1) holding `x`, and x's position within it in [0, 1).
fn sample_cdf(cdf: &[f32], x: f64) -> (usize, f64) {
    let n = cdf.len() - 1;
    let i = cdf[1..n].partition_point(|c| *c as f64 <= x);
    let (a, b) = (cdf[i] as f64, cdf[i + 1] as f64);
    let f = if b > a { (x - a) / (b - a) } else { 0.0 };
    (i, f.clamp(0.0, 1.0 - f64::EPSILON))
}

/// The inverse CDF at `xi` of the density on [0, 1] proportional to (1 − x) a + x b (a, b
/// non-negative; uniform when both are 0).
pub fn sample_linear(a: f64, b: f64, xi: f64) -> f64 {
    let denominator = a + (a * a + (b * b - a * a) * xi).sqrt();
    if denominator > 0.0 {
        (xi * (a + b) / denominator).clamp(0.0, 1.0)
    } else {
        xi
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

    const LAYOUTS: [TexelLayout; 2] = [TexelLayout::Centred, TexelLayout::PoleToPole];

    /// A map whose texels vary over two orders of magnitude, with one black texel.
    fn varied_map(width: u32, height: u32) -> EnvironmentMap {
        let texels = (0..width * height)
            .map(|k| {
                let l = if k == width + 1 {
                    0.0
                } else {
                    0.05 + (k * 7 % 11) as f32
                };
                [l, 0.5 * l, 0.1 + l]
            })
            .collect();
        EnvironmentMap::new(width, height, texels).unwrap()
    }

    /// A small deterministic generator of uniform numbers in [0, 1) (SplitMix64).
    struct Uniform(u64);

    impl Uniform {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn a_constant_map_is_the_constant_everywhere_and_its_mean() {
        let c = [0.25f32, 1.5, 3.0];
        let map = EnvironmentMap::new(5, 3, vec![c; 15]).unwrap();
        for layout in LAYOUTS {
            for (u, v) in [
                (0.0, 0.0),
                (1.0, 1.0),
                (0.05, 0.02),
                (0.5, 0.5),
                (0.97, 0.9),
                (0.3, 0.99),
            ] {
                assert_eq!(map.radiance(layout, u, v), c.map(f64::from), "{layout:?} at ({u}, {v})");
            }
            let d = map.distribution(layout);
            let relative = (d.mean_luminance - luminance(c)).abs() / luminance(c);
            assert!(relative < 1e-12, "{layout:?}: mean {}", d.mean_luminance);
        }
    }

    #[test]
    fn two_texel_maps_blend_bilinearly() {
        let (a, b) = ([1.0f32, 0.0, 2.0], [0.0f32, 4.0, 2.0]);
        let blend = |t: f64| std::array::from_fn::<f64, 3, _>(|c| a[c] as f64 * (1.0 - t) + b[c] as f64 * t);
        let close = |x: [f64; 3], y: [f64; 3]| x.iter().zip(&y).all(|(p, q)| (p - q).abs() < 1e-9);
        // 2 x 1: a at u = 1/4 (looking along -X), b at u = 3/4 (+X), wrapping through u = 0
        // (+Z); constant in v in both layouts.
        let wide = EnvironmentMap::new(2, 1, vec![a, b]).unwrap();
        let s = std::f64::consts::FRAC_1_SQRT_2;
        for layout in LAYOUTS {
            for (d, t) in [
                ([-1.0, 0.0, 0.0], 0.0),
                ([1.0, 0.0, 0.0], 1.0),
                ([0.0, 0.0, -1.0], 0.5),
                ([0.0, 0.0, 1.0], 0.5),
                ([0.0, 0.6, 0.8], 0.5),
                ([-s, 0.0, -s], 0.25),
                ([s, 0.0, s], 0.75),
                ([-0.6, -0.8, 0.0], 0.0),
            ] {
                let (u, v) = uv(d);
                let got = wide.radiance(layout, u, v);
                assert!(close(got, blend(t)), "{layout:?} 2 x 1 towards {d:?}: {got:?}");
            }
        }
        // 1 x 2: a on top, b below; constant in u.
        let tall = EnvironmentMap::new(1, 2, vec![a, b]).unwrap();
        for (layout, v, t) in [
            (TexelLayout::Centred, 0.0, 0.0),
            (TexelLayout::Centred, 0.25, 0.0),
            (TexelLayout::Centred, 0.375, 0.25),
            (TexelLayout::Centred, 0.5, 0.5),
            (TexelLayout::Centred, 0.8, 1.0),
            (TexelLayout::Centred, 1.0, 1.0),
            (TexelLayout::PoleToPole, 0.0, 0.0),
            (TexelLayout::PoleToPole, 0.25, 0.25),
            (TexelLayout::PoleToPole, 0.5, 0.5),
            (TexelLayout::PoleToPole, 0.8, 0.8),
            (TexelLayout::PoleToPole, 1.0, 1.0),
        ] {
            for u in [0.0, 0.3, 0.9] {
                let (u2, v2) = uv(direction(u, v));
                let got = tall.radiance(layout, u2, v2);
                assert!(close(got, blend(t)), "{layout:?} 1 x 2 at v = {v}: {got:?}");
            }
        }
    }

    /// The radiance a white Lambertian surface facing `normal` reflects under `map` (its
    /// irradiance over π), by the midpoint rule on an `n` × 2`n` grid in (θ, φ).
    fn lambertian_radiance(map: &EnvironmentMap, layout: TexelLayout, normal: [f64; 3], n: usize) -> [f64; 3] {
        let (dt, dp) = (PI / n as f64, PI / n as f64);
        let mut sum = [0.0; 3];
        for i in 0..n {
            let v = (i as f64 + 0.5) / n as f64;
            for j in 0..2 * n {
                let u = (j as f64 + 0.5) / (2 * n) as f64;
                let d = direction(u, v);
                let cos = d.iter().zip(&normal).map(|(a, b)| a * b).sum::<f64>();
                if cos > 0.0 {
                    let l = map.radiance(layout, u, v);
                    for c in 0..3 {
                        sum[c] += l[c] * cos * (PI * v).sin() * dt * dp / PI;
                    }
                }
            }
        }
        sum
    }

    /// A map, its layout, a surface normal and the closed form of the radiance reflected
    /// in a channel whose two texels are (a, b).
    type Case<'a> = (&'a EnvironmentMap, TexelLayout, [f64; 3], fn(f64, f64) -> f64);

    #[test]
    fn two_texel_maps_light_a_lambertian_surface_as_the_integration_tests_expect() {
        // The closed forms tests/integration/lights.rs compares renders with, for a = 0, b = 1
        // in one channel and the reverse in another: a wall facing +X under a 2 x 1 map
        // reflects (a + b + 2 (b − a) / π) / 2; a floor facing +Y under a 1 x 2 map (a on top)
        // reflects (3a + b) / 4 from pole to pole and a + (b − a)(1/4 − 1/(2π)) centred.
        let (a, b) = ([0.0f32, 1.0, 0.5], [1.0f32, 0.0, 0.5]);
        let wide = EnvironmentMap::new(2, 1, vec![a, b]).unwrap();
        let tall = EnvironmentMap::new(1, 2, vec![a, b]).unwrap();
        let cases: [Case; 4] = [
            (&wide, TexelLayout::Centred, [1.0, 0.0, 0.0], |a, b| {
                (a + b + 2.0 * (b - a) / PI) / 2.0
            }),
            (&wide, TexelLayout::PoleToPole, [1.0, 0.0, 0.0], |a, b| {
                (a + b + 2.0 * (b - a) / PI) / 2.0
            }),
            (&tall, TexelLayout::PoleToPole, [0.0, 1.0, 0.0], |a, b| {
                (3.0 * a + b) / 4.0
            }),
            (&tall, TexelLayout::Centred, [0.0, 1.0, 0.0], |a, b| {
                a + (b - a) * (0.25 - 0.5 / PI)
            }),
        ];
        for (map, layout, normal, closed_form) in cases {
            let got = lambertian_radiance(map, layout, normal, 400);
            for c in 0..3 {
                let expected = closed_form(a[c] as f64, b[c] as f64);
                assert!(
                    (got[c] - expected).abs() < 1e-4,
                    "{}x{} {layout:?} channel {c}: {} against {expected}",
                    map.width,
                    map.height,
                    got[c]
                );
            }
        }
    }

    #[test]
    fn linear_sampling_inverts_its_cdf() {
        for (a, b) in [(1.0, 1.0), (0.0, 2.0), (3.0, 0.0), (0.2, 5.0), (0.0, 0.0)] {
            for xi in [0.0, 0.1, 0.5, 0.77, 0.999] {
                let x: f64 = sample_linear(a, b, xi);
                let cdf = if a + b > 0.0 {
                    (a * x + (b - a) * x * x / 2.0) * 2.0 / (a + b)
                } else {
                    x
                };
                assert!((cdf - xi).abs() < 1e-12, "a {a}, b {b}: F({x}) = {cdf}, not {xi}");
            }
        }
    }

    /// Integrates the solid-angle density over the sphere by the midpoint rule in (θ, φ) on
    /// an `n` × 2`n` grid.
    fn sphere_integral(d: &Distribution, n: usize) -> f64 {
        let (dt, dp) = (PI / n as f64, PI / n as f64);
        let mut sum = 0.0;
        for i in 0..n {
            let theta = (i as f64 + 0.5) * dt;
            for j in 0..2 * n {
                let phi = (j as f64 + 0.5) * dp;
                let dir = [theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()];
                let (u, v) = uv(dir);
                let solid_angle_pdf = d.pdf(u, v) / (2.0 * PI * PI * theta.sin());
                sum += solid_angle_pdf * theta.sin() * dt * dp;
            }
        }
        sum
    }

    #[test]
    fn the_pdf_integrates_to_one_over_the_sphere() {
        let black = EnvironmentMap::new(3, 2, vec![[0.0; 3]; 6]).unwrap();
        for map in [varied_map(7, 5), varied_map(2, 1), varied_map(1, 3), black] {
            for layout in LAYOUTS {
                let d = map.distribution(layout);
                // The density is bilinear in (u, v) within each patch, and (u, v) are linear in
                // (θ, φ); the grid's cells do not straddle the patches' edges here (the edges
                // fall on multiples of π/420 and 2π/840), so the midpoint rule is exact up to
                // the rounding of the f32 densities.
                let integral = sphere_integral(&d, 420);
                assert!(
                    (integral - 1.0).abs() < 1e-6,
                    "{}x{} {layout:?}: {integral}",
                    map.width,
                    map.height
                );
            }
        }
    }

    /// The upper tail of the chi-square distribution with `dof` degrees of freedom beyond
    /// `x`, as a standard normal deviate (Wilson and Hilferty's cube-root approximation).
    fn chi_square_deviate(x: f64, dof: f64) -> f64 {
        let k = 2.0 / (9.0 * dof);
        ((x / dof).cbrt() - (1.0 - k)) / k.sqrt()
    }

    #[test]
    fn samples_follow_the_pdf() {
        let map = varied_map(6, 4);
        for layout in LAYOUTS {
            let d = map.distribution(layout);
            let p = d.patches;
            // Each patch split in 2 x 2 bins, whose probability the midpoint rule gives
            // exactly (the density is bilinear in each).
            let bins = p.rows() * p.width as usize * 4;
            let bin = |q: &PatchPoint| {
                (q.row * p.width as usize + q.col) * 4 + (q.st[0] >= 0.5) as usize + 2 * (q.st[1] >= 0.5) as usize
            };
            let mut expected = vec![0.0; bins];
            for row in 0..p.rows() {
                let dv = p.edge(row + 1) - p.edge(row);
                for col in 0..p.width as usize {
                    for (s, t) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                        let q = PatchPoint { row, col, st: [s, t] };
                        let (u, v) = p.uv(&q);
                        expected[bin(&q)] = d.pdf(u, v) * dv / p.width as f64 / 4.0;
                    }
                }
            }
            assert!((expected.iter().sum::<f64>() - 1.0).abs() < 1e-5);
            let n = 200_000;
            let mut observed = vec![0.0; bins];
            let mut rng = Uniform(7);
            for _ in 0..n {
                let (u, v) = d.sample([rng.next(), rng.next()]);
                assert!(d.pdf(u, v) > 0.0, "a sample at ({u}, {v}) where the pdf is 0");
                observed[bin(&p.locate(u, v))] += 1.0;
            }
            let (mut chi2, mut dof) = (0.0, -1.0);
            for (o, e) in observed.iter().zip(&expected) {
                let e = e * n as f64;
                if e > 0.0 {
                    chi2 += (o - e) * (o - e) / e;
                    dof += 1.0;
                } else {
                    assert_eq!(*o, 0.0, "a sample where the pdf is 0");
                }
            }
            let z = chi_square_deviate(chi2, dof);
            assert!(z < 4.5, "{layout:?}: chi2 {chi2} with {dof} dof ({z:.1} sigma)");
        }
    }

    #[test]
    fn black_texels_are_sampled_only_in_patches_a_neighbour_lights() {
        // 4 x 4: the top two rows black, one lit texel at (2, 3), the rest black.
        let mut texels = vec![[0.0f32; 3]; 16];
        texels[3 * 4 + 2] = [1.0, 2.0, 3.0];
        let map = EnvironmentMap::new(4, 4, texels).unwrap();
        for layout in LAYOUTS {
            let d = map.distribution(layout);
            let p = d.patches;
            let lit = |q: &PatchPoint| p.corners(q.row, q.col).contains(&14);
            let mut rng = Uniform(3);
            for _ in 0..20_000 {
                let (u, v) = d.sample([rng.next(), rng.next()]);
                assert!(
                    lit(&p.locate(u, v)),
                    "{layout:?}: sample at ({u}, {v}) in a black patch"
                );
            }
            // Wherever the filtered radiance is nonzero the pdf is too, and where it is 0 (a
            // patch with four black corners) the pdf is 0.
            for i in 0..200 {
                for j in 0..100 {
                    let (u, v) = ((i as f64 + 0.5) / 200.0, (j as f64 + 0.5) / 100.0);
                    let lum = map.radiance(layout, u, v)[1];
                    let pdf = d.pdf(u, v);
                    assert_eq!(
                        lum > 0.0,
                        pdf > 0.0,
                        "{layout:?} at ({u}, {v}): radiance {lum}, pdf {pdf}"
                    );
                    if !lit(&p.locate(u, v)) {
                        assert_eq!(pdf, 0.0);
                    }
                }
            }
        }
    }

    #[test]
    fn patches_locate_and_place_points_inversely() {
        for layout in LAYOUTS {
            let p = Patches {
                width: 5,
                height: 4,
                layout,
            };
            for (u, v) in [(0.0, 0.0), (0.05, 0.1), (0.5, 0.5), (0.93, 0.99), (0.3, 1.0)] {
                let q = p.locate(u, v);
                let (u2, v2) = p.uv(&q);
                assert!(
                    (u - u2).abs().min(1.0 - (u - u2).abs()) < 1e-12 && (v - v2).abs() < 1e-12,
                    "{layout:?}: ({u}, {v}) -> {q:?} -> ({u2}, {v2})"
                );
            }
            assert_eq!(p.edge(0), 0.0);
            assert_eq!(p.edge(p.rows()), 1.0);
        }
    }

    #[test]
    fn the_layout_is_read_from_a_scene_file_and_reaches_the_gpu() {
        use crate::model::Light;
        let scene = |layout: &str| {
            let text = format!(
                "Scene(camera: (position: (0, 3, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 20.0),
                    materials: {{\"white\": (diffuse: (1, 1, 1))}},
                    shapes: [Quad(corners: ((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)), material: \"white\")],
                    lights: [Environment(file: \"two.exr\"{layout})])"
            );
            let mut scene = crate::parse::scene_file::parse_scene("two.ron", &text).unwrap();
            let Light::Environment { map, .. } = &mut scene.lights[0] else {
                panic!()
            };
            *map = Some(std::sync::Arc::new(varied_map(3, 2)));
            crate::pack::compile::CompiledScene::new(&scene).unwrap()
        };
        for (text, layout, rows) in [
            ("", TexelLayout::Centred, 3),
            (", layout: Centred", TexelLayout::Centred, 3),
            (", layout: PoleToPole", TexelLayout::PoleToPole, 1),
        ] {
            let compiled = scene(text);
            assert_eq!(
                compiled.environment.pole_to_pole,
                (layout == TexelLayout::PoleToPole) as u32
            );
            let d = varied_map(3, 2).distribution(layout);
            assert_eq!(d.patches.rows(), rows);
            assert_eq!(compiled.env_cdf.len(), rows * 4 + 2 * rows + 1, "{text}");
            assert_eq!((compiled.env_cdf, compiled.env_texels), (d.cdf, d.texels));
        }
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
