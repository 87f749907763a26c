//! Media as the GPU reads them: the media in name order, each material's interior and
//! exterior medium, and the camera's (docs/media.md).

use crate::gpu::{GpuMaterialMedia, GpuMediaInfo, GpuMedium};
use crate::model::Scene;
use crate::model::media::unknown_medium;

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
    let mut media: Vec<GpuMedium> = scene
        .media
        .values()
        .map(|m| GpuMedium {
            sigma_s: m.sigma_s_scaled(),
            g: m.phase.g(),
            sigma_t: m.sigma_t(),
            kind: 0,
        })
        .collect();
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
    Ok(PackedMedia {
        media,
        material_media,
        info: GpuMediaInfo {
            camera_medium,
            count,
            pad: [0; 2],
        },
    })
}
