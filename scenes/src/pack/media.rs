//! Media as the GPU reads them: the media in name order, each material's interior and
//! exterior medium, the camera's, and the density grids of heterogeneous media
//! (docs/media.md).

use crate::gpu::{GpuDensityGrid, GpuMaterialMedia, GpuMediaInfo, GpuMedium};
use crate::model::Scene;
use crate::model::grid::{GridFilter, invert_affine};
use crate::model::media::{Medium, unknown_medium};

/// The scene's media packed for the GPU. Buffers are never empty: a scene without media has
/// one zero medium and one vacuum pair.
#[derive(Debug, Clone)]
pub struct PackedMedia {
    /// The media, in name order.
    pub media: Vec<GpuMedium>,
    /// Per material, in name order: its sides' media.
    pub material_media: Vec<GpuMaterialMedia>,
    /// The camera's medium and the count.
    pub info: GpuMediaInfo,
    /// The heterogeneous media's density grids (one zero grid when there are none).
    pub grids: Vec<GpuDensityGrid>,
    /// Their densities, one grid after another (one zero when there are none).
    pub density: Vec<f32>,
}

impl PackedMedia {
    /// Whether a medium has a density grid.
    pub fn has_grids(&self) -> bool {
        self.media[..self.info.count as usize].iter().any(|m| m.kind != 0)
    }
}

/// Packs the scene's media, naming an unknown medium.
pub fn pack(scene: &Scene) -> Result<PackedMedia, String> {
    let index = |name: &Option<String>| -> Result<i32, String> {
        match name {
            None => Ok(-1),
            Some(n) => scene
                .media
                .keys()
                .position(|k| k == n)
                .map(|i| i as i32)
                .ok_or_else(|| unknown_medium(n, scene)),
        }
    };
    let mut grids = Vec::new();
    let mut density = Vec::new();
    let mut media = Vec::new();
    for (name, m) in &scene.media {
        let kind = match &m.grid {
            None => 0,
            Some(_) => {
                grids.push(pack_grid(m, &mut density).map_err(|e| format!("medium '{name}': {e}"))?);
                grids.len() as u32
            }
        };
        media.push(GpuMedium {
            sigma_s: m.sigma_s_scaled(),
            g: m.phase.g(),
            sigma_t: m.sigma_t(),
            kind,
        });
    }
    let mut material_media = scene
        .materials
        .iter()
        .map(|(name, m)| {
            Ok(GpuMaterialMedia {
                interior: index(&m.interior).map_err(|e| format!("material '{name}': {e}"))?,
                exterior: index(&m.exterior).map_err(|e| format!("material '{name}': {e}"))?,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    let camera_medium = index(&scene.camera_medium).map_err(|e| format!("camera_medium: {e}"))?;
    let count = media.len() as u32;
    if media.is_empty() {
        media.push(GpuMedium::default());
    }
    if material_media.is_empty() {
        material_media.push(GpuMaterialMedia {
            interior: -1,
            exterior: -1,
        });
    }
    if grids.is_empty() {
        grids.push(GpuDensityGrid::default());
        density.push(0.0);
    }
    Ok(PackedMedia {
        media,
        material_media,
        info: GpuMediaInfo {
            camera_medium,
            count,
            pad: [0; 2],
        },
        grids,
        density,
    })
}

/// The density grid of heterogeneous medium `m`, its densities appended to `density`.
fn pack_grid(m: &Medium, density: &mut Vec<f32>) -> Result<GpuDensityGrid, String> {
    let grid = m.grid.as_ref().expect("a heterogeneous medium");
    let volume = grid
        .volume
        .as_ref()
        .ok_or_else(|| format!("its grid '{}' was not read", grid.file))?;
    let to_grid = invert_affine(&grid.to_world)
        .ok_or_else(|| format!("its grid's to_world {:?} is not invertible", grid.to_world))?;
    let at = |density: &Vec<f32>| {
        u32::try_from(density.len()).map_err(|_| "the density grids exceed 2^32 values".to_string())
    };
    let offset = at(density)?;
    density.extend_from_slice(&volume.data);
    let majorant_offset = at(density)?;
    let majorants = volume.majorants();
    density.extend_from_slice(&majorants.data);
    Ok(GpuDensityGrid {
        to_grid,
        res: volume.res,
        offset,
        cells: majorants.res,
        majorant_offset,
        nearest: (grid.filter == GridFilter::Nearest) as u32,
        pad: [0; 3],
    })
}
