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

impl VolumeGrid {
    /// The largest density: a majorant of the trilinear interpolation and of the nearest
    /// voxel alike.
    pub fn max(&self) -> f32 {
        self.data.iter().fold(0.0, |m, &d| m.max(d))
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
        assert_eq!(g.max(), 23.0);
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
