//! Result files: 32-bit float EXR with metadata, and sRGB PNG previews.

use crate::render::Image;
use anyhow::{Context, Result};
use std::path::Path;

/// Writes the mean radiance as a 32-bit float RGB EXR with `metadata` as string attributes.
pub fn write_exr(path: &Path, image: &Image, metadata: &[(&str, String)]) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::*;
    let w = image.width as usize;
    let mut attributes = LayerAttributes::named("radiance");
    attributes.software_name = Some(Text::from("lightgraph"));
    for (k, v) in metadata {
        attributes.other.insert(
            Text::from(format!("lightgraph.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let layer = Layer::new(
        (w, image.height as usize),
        attributes,
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = image.mean[p.y() * w + p.x()];
            (c[0], c[1], c[2])
        }),
    );
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

fn srgb_encode(linear: f32) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let s = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes an 8-bit sRGB preview, the radiance scaled by 2^`exposure` and clamped.
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    let scale = exposure.exp2();
    let bytes: Vec<u8> = image
        .mean
        .iter()
        .flat_map(|c| c.map(|v| srgb_encode(v * scale)))
        .collect();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    image::save_buffer(path, &bytes, image.width, image.height, image::ColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_end_points() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        assert_eq!(srgb_encode(2.0), 255);
        assert_eq!(srgb_encode(0.5), 188);
    }
}
