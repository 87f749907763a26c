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
    write_whole(path, |partial| {
        exr::prelude::Image::from_layer(layer)
            .write()
            .to_file(partial)
            .map_err(|e| anyhow!("{e}"))
    })
}

/// Writes the file `path` whole or not at all: `write` writes a partial file beside it (of
/// the same extension), which then replaces `path` in one rename, so that a process ended
/// while writing (a second Ctrl-C, a kill) leaves the earlier file intact.
fn write_whole(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
    let partial = path.with_file_name(format!(".partial-{name}"));
    let written = write(&partial).and_then(|()| Ok(std::fs::rename(&partial, path)?));
    if written.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    written.with_context(|| format!("writing {}", path.display()))
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
    check_is_exr(path)?;
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

/// Checks that `path` is an OpenEXR file by its first bytes, so that another file (a PNG
/// preview given for its film) is named as what it is, not as a broken EXR.
fn check_is_exr(path: &Path) -> Result<()> {
    use std::io::Read;
    if path.is_dir() {
        bail!(
            "{}: it is a folder, not an EXR film written by lightgraph",
            path.display()
        );
    }
    let mut magic = [0u8; 4];
    let read = std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .map(|()| magic);
    match read {
        Ok([0x76, 0x2f, 0x31, 0x01]) => Ok(()),
        Ok([0x89, b'P', b'N', b'G']) => bail!(
            "{}: a PNG image, not an EXR film written by lightgraph (give the .exr beside it)",
            path.display()
        ),
        Ok(_) => bail!(
            "{}: not an EXR film written by lightgraph (not an OpenEXR file)",
            path.display()
        ),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            bail!(
                "{}: not an EXR film written by lightgraph (too short for an OpenEXR file)",
                path.display()
            )
        }
        Err(e) => bail!("reading {}: {e}", path.display()),
    }
}

/// Writes an 8-bit sRGB preview, the radiance scaled by 2^`exposure` and clamped.
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    let png = png_bytes(image, exposure)?;
    write_whole(path, |partial| Ok(std::fs::write(partial, &png)?))
}

/// The PNG file of `image` at `exposure` stops (sRGB, 8 bits), as [`write_png`] writes it.
pub fn png_bytes(image: &Image, exposure: f32) -> Result<Vec<u8>> {
    let scale = exposure.exp2();
    let bytes: Vec<u8> = image
        .mean
        .iter()
        .flat_map(|c| c.map(|v| linear_to_srgb8(v * scale)))
        .collect();
    let mut png = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    image::ImageEncoder::write_image(
        encoder,
        &bytes,
        image.width,
        image.height,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(png)
}

/// Something a command writes: a file, or a folder holding the entries (files or folders)
/// the command writes into it.
#[derive(Debug, Clone, Copy)]
pub enum Output<'a> {
    /// A file: a film, its PNG preview, a report.
    File(&'a Path),
    /// A folder (created if missing) and the entries of it the command writes: only those
    /// count as an earlier run's output; other files in the folder are left alone.
    Folder(&'a Path, &'a [&'a str]),
}

/// Checks every output of a command before any work starts: each can be written (its
/// folder, or the nearest one above it that exists, is a folder this process can create
/// files in), and none exists already unless `force` (an existing output's error says to
/// give --force or another --out, and `resume`, where given, how to continue it instead).
pub fn check_outputs(outputs: &[Output], force: bool, resume: Option<&str>) -> Result<()> {
    let exists = |what: String| {
        let resume = resume.map_or_else(String::new, |r| format!("{r}, "));
        anyhow!("{what}: give {resume}--force to replace it, or another --out")
    };
    for output in outputs {
        match *output {
            Output::File(path) => {
                if path.is_dir() {
                    bail!("{}: it is a folder; give the path of a file", path.display());
                }
                if path.exists() && !force {
                    return Err(exists(format!("{} exists", path.display())));
                }
                let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
                check_folder_writable(folder.unwrap_or(Path::new(".")), path)?;
            }
            Output::Folder(folder, entries) => {
                if folder.exists() && !folder.is_dir() {
                    bail!("{}: it is a file, not a folder", folder.display());
                }
                let held: Vec<&str> = entries.iter().copied().filter(|e| folder.join(e).exists()).collect();
                if !held.is_empty() && !force {
                    return Err(exists(format!(
                        "{} holds the output of an earlier run ({})",
                        folder.display(),
                        held.join(", ")
                    )));
                }
                check_folder_writable(folder, folder)?;
            }
        }
    }
    Ok(())
}

/// Checks that files can be created in `folder` (for `output`), or, where it does not exist
/// yet, in the nearest folder above it that exists (where it will be created): that one must
/// be a folder, and a file created there (and removed at once) proves it writable.
fn check_folder_writable(folder: &Path, output: &Path) -> Result<()> {
    let mut existing = folder;
    while !existing.exists() {
        existing = match existing.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
    }
    if !existing.is_dir() {
        bail!(
            "{}: {} is a file, not a folder; give another --out",
            output.display(),
            existing.display()
        );
    }
    // Unique in the process too: two runs of one process (threads, the Python module) may
    // check one folder at once, and a shared probe name made one of them fail (EEXIST).
    static PROBES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = PROBES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let probe = existing.join(format!(".lightgraph-write-check-{}-{n}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => bail!(
            "{}: cannot write into {} ({e}); give another --out",
            output.display(),
            existing.display()
        ),
    }
}

/// Checks the film's path `out` and its PNG preview before any work: the film must be an
/// EXR, an existing film is replaced only with `--force` or added to with `--resume` (then
/// its preview too), and both must be writable ([`check_outputs`]).
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
    let advice = format!("--resume {} to add frames to it", out.display());
    let png = out.with_extension("png");
    check_outputs(
        &[Output::File(out), Output::File(&png)],
        force || resuming_it,
        (out.exists() && !resuming_it).then_some(advice.as_str()),
    )
}

/// Whether `a` and `b` name the same file (by their canonical paths where they exist).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// `path` as one word of a shell command: as it is where it has only letters, digits and
/// `_./:,+=@%-`, else in single quotes.
pub fn shell_word(path: &Path) -> String {
    let text = path.display().to_string();
    let plain = |c: char| c.is_ascii_alphanumeric() || "_./:,+=@%-".contains(c);
    match !text.is_empty() && text.chars().all(plain) {
        true => text,
        false => format!("'{}'", text.replace('\'', "'\\''")),
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
    fn threads_of_one_process_check_one_folder_at_once() {
        // Two renders of one test process checked one folder at once and one failed with
        // "cannot write into ... (File exists)": the probe was named by the process alone.
        let dir = std::env::temp_dir().join(format!("lightgraph-probe-race-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let failures: usize = std::thread::scope(|s| {
            let handles: Vec<_> = (0..8)
                .map(|_| {
                    s.spawn(|| {
                        (0..200)
                            .filter(|_| check_folder_writable(&dir, &dir.join("film.exr")).is_err())
                            .count()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).sum()
        });
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(failures, 0, "checks of one folder failed when run at once");
    }

    #[test]
    fn a_path_is_one_shell_word() {
        assert_eq!(shell_word(Path::new("out/film-1.exr")), "out/film-1.exr");
        assert_eq!(shell_word(Path::new("my film.exr")), "'my film.exr'");
        assert_eq!(shell_word(Path::new("it's.exr")), "'it'\\''s.exr'");
    }

    #[test]
    fn a_folders_own_entries_count_as_an_earlier_run_and_others_do_not() {
        let dir = std::env::temp_dir().join(format!("lightgraph-check-outputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("notes.txt"), "").unwrap();
        assert!(check_outputs(&[Output::Folder(&dir, &["bench.md"])], false, None).is_ok());
        std::fs::write(dir.join("bench.md"), "").unwrap();
        let err = check_outputs(&[Output::Folder(&dir, &["bench.md"])], false, None).unwrap_err();
        assert!(err.to_string().contains("(bench.md)"), "{err}");
        assert!(check_outputs(&[Output::Folder(&dir, &["bench.md"])], true, None).is_ok());
        // The probe file leaves nothing behind.
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn srgb_curve_end_points() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(2.0), 255);
        assert_eq!(linear_to_srgb8(0.5), 188);
    }
}
