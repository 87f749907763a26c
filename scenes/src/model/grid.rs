//! Density grids of heterogeneous media (docs/media.md): where a medium's grid lies and how it
//! is filtered, and Mitsuba's `.vol` files that hold the densities.

use serde::Deserialize;
use std::sync::Arc;

/// A medium's density grid: the `.vol` file that holds it, the box it fills and its filter.
/// The medium's coefficients are per unit density; outside the box the density is zero.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DensityGrid {
    /// The `.vol` file (Mitsuba's format), relative to the scene file.
    pub file: String,
    /// The affine map (three rows of a 4 x 4 matrix) from the unit cube (0, 0, 0)–(1, 1, 1),
    /// where the grid lies, to the world: Mitsuba's gridvolume `to_world`. Default: identity.
    #[serde(default = "identity")]
    pub to_world: [[f32; 4]; 3],
    /// How densities between voxel centres are found.
    #[serde(default)]
    pub filter: GridFilter,
    /// The densities, once read (the scene's loading fills this).
    #[serde(skip)]
    pub volume: Option<Arc<VolumeGrid>>,
}

/// How a grid is looked up between its voxel centres (Mitsuba's gridvolume `filter_type`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
pub enum GridFilter {
    /// Trilinear interpolation of the eight nearest voxel centres (Mitsuba's default).
    #[default]
    Trilinear,
    /// The voxel the point lies in.
    Nearest,
}

/// The identity's three rows.
pub fn identity() -> [[f32; 4]; 3] {
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
}

/// A grid of densities read from a `.vol` file: `res` voxels per axis, x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeGrid {
    /// Voxels along x, y and z.
    pub res: [u32; 3],
    /// The bounding box the file gives (min, max): used only where Mitsuba's `use_grid_bbox`
    /// asks for it.
    pub bbox: [[f32; 3]; 2],
    /// The densities, `data[(z * res_y + y) * res_x + x]`.
    pub data: Vec<f32>,
}

/// The most cells of a majorant grid along an axis.
pub const MAJORANT_CELLS: u32 = 16;

impl VolumeGrid {
    /// The coarse grid of majorants over the unit cube: up to [`MAJORANT_CELLS`] cells an axis
    /// (no more than the voxels), each holding the largest density of the voxels that a
    /// trilinear or nearest lookup anywhere in the cell reads (clamped at the faces).
    pub fn majorants(&self) -> VolumeGrid {
        let cells = self.res.map(|r| r.min(MAJORANT_CELLS));
        // The voxels a lookup in cell c of n along an axis of `res` voxels reads: from the
        // one below the cell's low end's centre to the one above its high end's.
        let span = |c: u32, n: u32, res: u32| -> (usize, usize) {
            let voxel = |u: f64| (u * res as f64 - 0.5).floor();
            let lo = voxel(c as f64 / n as f64).max(0.0) as usize;
            let hi = (voxel((c + 1) as f64 / n as f64) + 1.0).clamp(0.0, (res - 1) as f64) as usize;
            (lo, hi)
        };
        let mut data = Vec::with_capacity(cells.iter().product::<u32>() as usize);
        let (rx, ry) = (self.res[0] as usize, self.res[1] as usize);
        for cz in 0..cells[2] {
            let (z0, z1) = span(cz, cells[2], self.res[2]);
            for cy in 0..cells[1] {
                let (y0, y1) = span(cy, cells[1], self.res[1]);
                for cx in 0..cells[0] {
                    let (x0, x1) = span(cx, cells[0], self.res[0]);
                    let mut m = 0f32;
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            let row = (z * ry + y) * rx;
                            m = self.data[row + x0..=row + x1].iter().fold(m, |m, &d| m.max(d));
                        }
                    }
                    data.push(m);
                }
            }
        }
        VolumeGrid {
            res: cells,
            bbox: self.bbox,
            data,
        }
    }

    /// Reads Mitsuba's `.vol` format: 'V', 'O', 'L', version 3, then little-endian int32s
    /// encoding (1: float32), x, y and z resolutions and channels (1 here: a density), six
    /// float32s of a bounding box (Mitsuba 3 ignores it unless asked; so does this), then
    /// the float32 densities, x fastest. Densities must be finite and not negative.
    pub fn from_vol(bytes: &[u8]) -> Result<VolumeGrid, String> {
        const HEADER: usize = 48;
        if bytes.len() < HEADER {
            return Err(format!(
                "{} bytes: shorter than a .vol header ({HEADER} bytes)",
                bytes.len()
            ));
        }
        if &bytes[..3] != b"VOL" {
            return Err(format!(
                "not a .vol file: it starts with {:?}, not \"VOL\"",
                &bytes[..3]
            ));
        }
        if bytes[3] != 3 {
            return Err(format!(
                "version {} of the .vol format: only version 3 is read",
                bytes[3]
            ));
        }
        let int = |at: usize| i32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes"));
        let encoding = int(4);
        if encoding != 1 {
            return Err(format!("encoding {encoding}: only 1 (float32) is read"));
        }
        let res = [int(8), int(12), int(16)];
        if res.iter().any(|&r| r <= 0) {
            return Err(format!("resolution {res:?}: every axis needs a voxel at least"));
        }
        let channels = int(20);
        if channels != 1 {
            return Err(format!("{channels} channels: a density grid has one"));
        }
        let count = res.iter().map(|&r| r as u64).product::<u64>();
        let expected = HEADER as u64 + 4 * count;
        if bytes.len() as u64 != expected {
            return Err(format!(
                "{} bytes, but a {}x{}x{} grid of one float32 channel takes {expected}",
                bytes.len(),
                res[0],
                res[1],
                res[2]
            ));
        }
        let data: Vec<f32> = bytes[HEADER..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("four bytes")))
            .collect();
        if let Some(i) = data.iter().position(|d| !d.is_finite() || *d < 0.0) {
            let (x, y) = (res[0] as usize, res[1] as usize);
            return Err(format!(
                "the density {} of voxel ({}, {}, {}) is not finite and non-negative",
                data[i],
                i % x,
                i / x % y,
                i / (x * y)
            ));
        }
        let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes"));
        Ok(VolumeGrid {
            res: res.map(|r| r as u32),
            bbox: [[float(24), float(28), float(32)], [float(36), float(40), float(44)]],
            data,
        })
    }
}

impl VolumeGrid {
    /// The grid in Mitsuba's `.vol` format, as [`VolumeGrid::from_vol`] reads it.
    pub fn to_vol(&self) -> Vec<u8> {
        let mut out = b"VOL\x03".to_vec();
        for i in [1, self.res[0], self.res[1], self.res[2], 1] {
            out.extend(i.to_le_bytes());
        }
        for f in self.bbox.iter().flatten().chain(&self.data) {
            out.extend(f.to_le_bytes());
        }
        out
    }
}

/// The inverse of the affine map `m` (three rows), or None where it is singular.
pub fn invert_affine(m: &[[f32; 4]; 3]) -> Option<[[f32; 4]; 3]> {
    let a = |r: usize, c: usize| m[r][c] as f64;
    let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    // The adjugate over the determinant, then the translation taken back.
    let cof = |r0: usize, r1: usize, c0: usize, c1: usize| a(r0, c0) * a(r1, c1) - a(r0, c1) * a(r1, c0);
    let inv = [
        [cof(1, 2, 1, 2), -cof(0, 2, 1, 2), cof(0, 1, 1, 2)],
        [-cof(1, 2, 0, 2), cof(0, 2, 0, 2), -cof(0, 1, 0, 2)],
        [cof(1, 2, 0, 1), -cof(0, 2, 0, 1), cof(0, 1, 0, 1)],
    ]
    .map(|row| row.map(|v| v / det));
    let t = [a(0, 3), a(1, 3), a(2, 3)];
    Some(std::array::from_fn(|r| {
        let shift = -(inv[r][0] * t[0] + inv[r][1] * t[1] + inv[r][2] * t[2]);
        [inv[r][0] as f32, inv[r][1] as f32, inv[r][2] as f32, shift as f32]
    }))
}

#[cfg(test)]
pub mod tests {
    use super::*;

    /// A `.vol` file of `res` voxels holding `data`, whose box is (0, 0, 0)-(1, 2, 3).
    pub fn vol_bytes(res: [u32; 3], data: &[f32]) -> Vec<u8> {
        VolumeGrid {
            res,
            bbox: [[0.0; 3], [1.0, 2.0, 3.0]],
            data: data.to_vec(),
        }
        .to_vol()
    }

    #[test]
    fn a_vol_file_is_read_x_fastest() {
        let data: Vec<f32> = (0..24).map(|i| i as f32).collect();
        let g = VolumeGrid::from_vol(&vol_bytes([2, 3, 4], &data)).unwrap();
        assert_eq!(g.res, [2, 3, 4]);
        assert_eq!(g.data, data);
        assert_eq!(g.bbox, [[0.0; 3], [1.0, 2.0, 3.0]]);
    }

    #[test]
    fn bad_vol_files_are_refused_with_what_is_wrong() {
        let good = vol_bytes([2, 2, 2], &[1.0; 8]);
        let with = |at: usize, b: &[u8]| {
            let mut v = good.clone();
            v[at..at + b.len()].copy_from_slice(b);
            VolumeGrid::from_vol(&v).unwrap_err()
        };
        assert!(with(0, b"VOX").contains("not a .vol file"));
        assert!(with(3, &[2]).contains("version 2"));
        assert!(with(4, &2i32.to_le_bytes()).contains("encoding 2"));
        assert!(with(20, &3i32.to_le_bytes()).contains("3 channels"));
        assert!(with(8, &0i32.to_le_bytes()).contains("resolution [0, 2, 2]"));
        let e = VolumeGrid::from_vol(&good[..good.len() - 4]).unwrap_err();
        assert!(
            e.contains("76 bytes, but a 2x2x2 grid of one float32 channel takes 80"),
            "{e}"
        );
        assert!(with(48 + 4 * 5, &(-1f32).to_le_bytes()).contains("density -1 of voxel (1, 0, 1)"));
        assert!(with(48, &f32::NAN.to_le_bytes()).contains("voxel (0, 0, 0)"));
        assert!(
            VolumeGrid::from_vol(&good[..10])
                .unwrap_err()
                .contains("shorter than a .vol header")
        );
    }

    /// The trilinear density of `g` at `u` in the unit cube (voxel centres at (i + 0.5) / res,
    /// clamped), as shaders/lib/media_grid.wgsl looks it up.
    fn trilinear(g: &VolumeGrid, u: [f64; 3]) -> f64 {
        let s: [f64; 3] = std::array::from_fn(|k| u[k] * g.res[k] as f64 - 0.5);
        let voxel = |i: [i64; 3]| {
            let c: [usize; 3] = std::array::from_fn(|k| i[k].clamp(0, g.res[k] as i64 - 1) as usize);
            g.data[(c[2] * g.res[1] as usize + c[1]) * g.res[0] as usize + c[0]] as f64
        };
        let mut sum = 0.0;
        for corner in 0..8 {
            let mut w = 1.0;
            let i: [i64; 3] = std::array::from_fn(|k| {
                let up = (corner >> k) & 1 == 1;
                let f = s[k] - s[k].floor();
                w *= if up { f } else { 1.0 - f };
                s[k].floor() as i64 + up as i64
            });
            sum += w * voxel(i);
        }
        sum
    }

    #[test]
    fn majorants_bound_every_lookup_in_their_cell_and_are_tight_on_a_constant_grid() {
        // A grid of 37 x 5 x 20 pseudo-random densities, most of them zero.
        let res = [37u32, 5, 20];
        let mut state = 12345u32;
        let data: Vec<f32> = (0..res.iter().product::<u32>())
            .map(|_| {
                state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                let v = (state >> 8) as f32 / 16777216.0;
                if v < 0.8 { 0.0 } else { v }
            })
            .collect();
        let g = VolumeGrid {
            res,
            bbox: [[0.0; 3], [1.0; 3]],
            data,
        };
        let m = g.majorants();
        assert_eq!(m.res, [16, 5, 16]);
        for i in 0..200_000u32 {
            let u: [f64; 3] =
                std::array::from_fn(|k| ((i as f64 + 0.5) * [0.754877666, 0.569840291, 0.362437524][k]).fract());
            let c: [usize; 3] = std::array::from_fn(|k| ((u[k] * m.res[k] as f64) as usize).min(m.res[k] as usize - 1));
            let bound = m.data[(c[2] * m.res[1] as usize + c[1]) * m.res[0] as usize + c[0]] as f64;
            let nearest: [usize; 3] =
                std::array::from_fn(|k| ((u[k] * res[k] as f64) as usize).min(res[k] as usize - 1));
            let near = g.data[(nearest[2] * res[1] as usize + nearest[1]) * res[0] as usize + nearest[0]] as f64;
            assert!(trilinear(&g, u) <= bound + 1e-6 && near <= bound, "{u:?} in cell {c:?}");
        }
        // Cells of zeros stay zero (the point of the grid), and a constant grid's are its value.
        assert!(m.data.iter().filter(|&&d| d == 0.0).count() > 0);
        let flat = VolumeGrid {
            res: [4, 4, 4],
            bbox: [[0.0; 3], [1.0; 3]],
            data: vec![2.0; 64],
        }
        .majorants();
        assert!(flat.data.iter().all(|&d| d == 2.0));
    }

    #[test]
    fn an_affine_map_is_inverted() {
        let m = [[2.0, 0.0, 0.0, -1.0], [0.0, 0.0, 3.0, 2.0], [0.0, 4.0, 0.0, 0.5]];
        let inv = invert_affine(&m).unwrap();
        let apply = |m: &[[f32; 4]; 3], p: [f32; 3]| -> [f32; 3] {
            std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
        };
        let p = [0.3, -0.7, 1.9];
        let back = apply(&inv, apply(&m, p));
        assert!((0..3).all(|i| (back[i] - p[i]).abs() < 1e-5), "{back:?}");
        assert!(invert_affine(&[[1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]).is_none());
    }
}
