//! Result files: 32-bit float EXR with metadata, and sRGB PNG previews; where a film may go.

use crate::run::Image;
use anyhow::{Context, Result, anyhow, bail};
use lightgraph_scenes::texture::linear_to_srgb8;
use std::collections::BTreeMap;
use std::path::Path;

/// Writes the mean radiance as a 32-bit float RGB EXR with `metadata` as string attributes.
pub fn write_exr(path: &Path, image: &Image, metadata: &[(&str, String)]) -> Result<()> {
    let channel = |c: usize| image.mean.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let channels = vec![
        ("R".into(), channel(0)),
        ("G".into(), channel(1)),
        ("B".into(), channel(2)),
    ];
    write_channels(path, (image.width, image.height), channels, metadata)
}

/// Writes named 32-bit float channels (row-major, top row first) as one EXR layer called
/// "radiance", with `metadata` as `lightgraph.KEY` string attributes.
pub fn write_channels(
    path: &Path,
    (width, height): (u32, u32),
    channels: Vec<(String, Vec<f32>)>,
    metadata: &[(&str, String)],
) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::*;
    let mut attributes = LayerAttributes::named("radiance");
    attributes.software_name = Some(Text::from("lightgraph"));
    for (k, v) in metadata {
        attributes.other.insert(
            Text::from(format!("lightgraph.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, values)| AnyChannel::new(name.as_str(), FlatSamples::F32(values)))
        .collect();
    let layer = Layer::new(
        (width as usize, height as usize),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
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

/// An EXR read back: its size, its channels as f32 and its `lightgraph.*` attributes.
#[derive(Debug, Clone)]
pub struct ExrFile {
    /// Width and height.
    pub size: (u32, u32),
    /// Channels by name (row-major, top row first).
    pub channels: BTreeMap<String, Vec<f32>>,
    /// The `lightgraph.KEY` text attributes, by KEY.
    pub metadata: BTreeMap<String, String>,
}

impl ExrFile {
    /// The channel called `name`, or an error naming the file and the channels it has.
    pub fn channel(&self, name: &str, path: &Path) -> Result<&[f32]> {
        self.channels.get(name).map(Vec::as_slice).ok_or_else(|| {
            anyhow!(
                "{}: no channel '{name}' (it has {})",
                path.display(),
                self.channels.keys().cloned().collect::<Vec<_>>().join(", ")
            )
        })
    }
}

/// Reads the first layer of an EXR file with all its channels and lightgraph attributes.
pub fn read_exr(path: &Path) -> Result<ExrFile> {
    use exr::meta::attribute::AttributeValue;
    let image =
        exr::prelude::read_first_flat_layer_from_file(path).with_context(|| format!("reading {}", path.display()))?;
    let layer = image.layer_data;
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    let metadata = layer
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => k
                .to_string()
                .strip_prefix("lightgraph.")
                .map(|k| (k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok(ExrFile {
        size: (layer.size.width() as u32, layer.size.height() as u32),
        channels,
        metadata,
    })
}

/// The R, G and B channels of an EXR as pixels: width, height and the pixels (row-major, top
/// row first).
pub fn read_rgb(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let exr = read_exr(path)?;
    let (r, g, b) = (
        exr.channel("R", path)?,
        exr.channel("G", path)?,
        exr.channel("B", path)?,
    );
    let rgb = r.iter().zip(g).zip(b).map(|((r, g), b)| [*r, *g, *b]).collect();
    Ok((exr.size.0, exr.size.1, rgb))
}

/// Writes an 8-bit sRGB preview, the radiance scaled by 2^`exposure` and clamped.
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    let scale = exposure.exp2();
    let bytes: Vec<u8> = image
        .mean
        .iter()
        .flat_map(|c| c.map(|v| linear_to_srgb8(v * scale)))
        .collect();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    image::save_buffer(path, &bytes, image.width, image.height, image::ColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Checks the film's path `out` before any work: it must be an EXR (the PNG preview goes beside
/// it), and an existing file is replaced only with `--force`, or added to with `--resume`.
pub fn check_out(out: &Path, force: bool, resume: Option<&Path>) -> Result<()> {
    let is_exr = out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        bail!(
            "--out {}: the film is an EXR (the PNG preview is written beside it): give a path ending in .exr, e.g. --out {}",
            out.display(),
            out.with_extension("exr").display()
        );
    }
    let resuming_it = resume.is_some_and(|r| same_file(r, out));
    if out.exists() && !force && !resuming_it {
        bail!(
            "--out {}: the file exists; give --resume {0} to add frames to it, --force to replace it, or another --out",
            out.display()
        );
    }
    Ok(())
}

/// Whether `a` and `b` name the same file (by their canonical paths where they exist).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// A number with an SI prefix and a trailing space, e.g. "1.28 G".
pub fn si(v: f64) -> String {
    match v {
        v if v >= 1e9 => format!("{:.2} G", v / 1e9),
        v if v >= 1e6 => format!("{:.2} M", v / 1e6),
        v if v >= 1e3 => format!("{:.2} k", v / 1e3),
        v => format!("{v:.1} "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_end_points() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(2.0), 255);
        assert_eq!(linear_to_srgb8(0.5), 188);
    }
}
