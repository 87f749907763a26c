//! Reference images: long progressive renders whose sums are kept on the host in f64, stored
//! as EXR with the mean radiance, its per-pixel variance and the settings that made it, and
//! resumable (more samples are added to a stored reference with the same settings).

use crate::output::{ExrFile, read_exr, write_channels};
use crate::render::{Accumulation, Image};
use anyhow::{Result, anyhow, bail};
use std::collections::BTreeMap;
use std::path::Path;

/// Settings that must be the same for every sample of a reference: the estimate they define.
pub const SETTINGS: [&str; 5] = ["scene", "graph", "samples_per_frame", "seed", "constants"];

/// A reference image being accumulated in f64: per pixel the sum of the frames' estimates
/// and of their squares.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Width and height.
    pub size: (u32, u32),
    /// Frames accumulated.
    pub frames: u64,
    /// Render seconds spent on it, over every run that added to it.
    pub seconds: f64,
    /// The [`SETTINGS`] and descriptive entries (layout, adapter) as text.
    pub info: BTreeMap<String, String>,
    sum: Vec<[f64; 3]>,
    sum_sq: Vec<[f64; 3]>,
}

impl Reference {
    /// An empty reference of `size` with the settings and description in `info`.
    pub fn new(size: (u32, u32), info: BTreeMap<String, String>) -> Reference {
        let n = size.0 as usize * size.1 as usize;
        Reference {
            size,
            frames: 0,
            seconds: 0.0,
            info,
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
        }
    }

    /// Adds the frames of a GPU accumulation (see
    /// [`crate::render::Session::take_accumulation`]).
    pub fn absorb(&mut self, taken: &Accumulation) {
        for ((s, q), (ts, tq)) in self
            .sum
            .iter_mut()
            .zip(&mut self.sum_sq)
            .zip(taken.sum.iter().zip(&taken.sum_sq))
        {
            for c in 0..3 {
                s[c] += ts[c] as f64;
                q[c] += tq[c] as f64;
            }
        }
        self.frames += taken.frames as u64;
    }

    /// Samples per pixel accumulated.
    pub fn samples_per_pixel(&self) -> u64 {
        self.frames
            * self
                .info
                .get("samples_per_frame")
                .and_then(|s| s.parse().ok())
                .unwrap_or(1)
    }

    /// Mean radiance per pixel.
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let n = self.frames.max(1) as f64;
        self.sum.iter().map(|s| s.map(|v| (v / n) as f32)).collect()
    }

    /// Per pixel, the estimated variance of the mean (the squared standard error): the
    /// sample variance of the frames' estimates over the number of frames; 0 with one frame.
    pub fn variance_of_mean(&self) -> Vec<[f32; 3]> {
        let n = self.frames as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| {
                [0, 1, 2].map(|c| {
                    if n < 2.0 {
                        return 0.0;
                    }
                    let m = s[c] / n;
                    ((q[c] / n - m * m).max(0.0) / (n - 1.0)) as f32
                })
            })
            .collect()
    }

    /// The reference's own expected squared error: the mean over pixels and channels of the
    /// variance of its mean. An image compared with the reference has an MSE of about its
    /// true MSE plus this floor.
    pub fn noise_floor_mse(&self) -> f64 {
        let v = self.variance_of_mean();
        v.iter().flat_map(|p| p.iter()).map(|&x| x as f64).sum::<f64>() / (v.len() * 3).max(1) as f64
    }

    /// The mean as an [`Image`] (for PNG previews); its variance is the per-frame one.
    pub fn image(&self) -> Image {
        let frames = self.frames.max(1) as f32;
        Image {
            width: self.size.0,
            height: self.size.1,
            frames: self.frames.min(u32::MAX as u64) as u32,
            mean: self.mean(),
            variance: self.variance_of_mean().iter().map(|v| v.map(|x| x * frames)).collect(),
        }
    }

    /// Writes the reference as an EXR: channels R, G, B (mean radiance) and variance.R,
    /// variance.G, variance.B (variance of the mean), with the settings, frames, samples per
    /// pixel and seconds as `lightgraph.*` attributes.
    pub fn write(&self, path: &Path) -> Result<()> {
        let mean = self.mean();
        let var = self.variance_of_mean();
        let channel = |v: &[[f32; 3]], c: usize| v.iter().map(|p| p[c]).collect::<Vec<f32>>();
        let mut channels = Vec::new();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            channels.push((name.to_string(), channel(&mean, c)));
            channels.push((format!("variance.{name}"), channel(&var, c)));
        }
        let mut meta: Vec<(&str, String)> = self.info.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
        meta.push(("kind", "reference".into()));
        meta.push(("frames", self.frames.to_string()));
        meta.push(("samples_per_pixel", self.samples_per_pixel().to_string()));
        meta.push(("seconds", format!("{:.3}", self.seconds)));
        write_channels(path, self.size, channels, &meta)
    }

    /// Reads a reference written by [`Reference::write`]; its f32 mean and variance give the
    /// sums back to about 1e-7 relative, far below any reference's noise.
    pub fn read(path: &Path) -> Result<Reference> {
        let file = read_exr(path)?;
        let frames = number(&file, path, "frames")?;
        let seconds = number(&file, path, "seconds")?;
        let mut info = file.metadata.clone();
        for key in ["kind", "frames", "samples_per_pixel", "seconds"] {
            info.remove(key);
        }
        if let Some(missing) = SETTINGS.iter().find(|k| !info.contains_key(**k)) {
            bail!(
                "{}: not a lightgraph reference (no '{missing}' attribute)",
                path.display()
            );
        }
        let mut reference = Reference::new(file.size, info);
        reference.frames = frames as u64;
        reference.seconds = seconds;
        let n = frames;
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let mean = file.channel(name, path)?;
            let var = file.channel(&format!("variance.{name}"), path)?;
            for (i, (&m, &v)) in mean.iter().zip(var).enumerate() {
                let (m, v) = (m as f64, v as f64);
                reference.sum[i][c] = m * n;
                // Inverse of variance_of_mean: sum_sq / n = v (n - 1) + m².
                reference.sum_sq[i][c] = n * (v * (n - 1.0).max(0.0) + m * m);
            }
        }
        Ok(reference)
    }

    /// Checks that the settings in `info` are those of this reference, naming each that
    /// differs.
    pub fn check_settings(&self, info: &BTreeMap<String, String>, path: &Path) -> Result<()> {
        let differ: Vec<String> = SETTINGS
            .iter()
            .filter(|k| self.info.get(**k) != info.get(**k))
            .map(|k| {
                format!(
                    "{k} is '{}' there, '{}' here",
                    self.info.get(*k).map_or("", String::as_str),
                    info.get(*k).map_or("", String::as_str)
                )
            })
            .collect();
        if !differ.is_empty() {
            bail!(
                "{}: the reference was made with other settings, so samples cannot be added to it: {}",
                path.display(),
                differ.join("; ")
            );
        }
        Ok(())
    }
}

fn number(file: &ExrFile, path: &Path, key: &str) -> Result<f64> {
    file.metadata
        .get(key)
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| {
            anyhow!(
                "{}: not a lightgraph reference (no valid '{key}' attribute)",
                path.display()
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info() -> BTreeMap<String, String> {
        SETTINGS
            .iter()
            .map(|k| (k.to_string(), format!("{k}-value")))
            .chain([("samples_per_frame".to_string(), "2".to_string())])
            .collect()
    }

    fn frames(values: &[[f32; 3]]) -> Accumulation {
        Accumulation {
            frames: values.len() as u32,
            sum: vec![
                values
                    .iter()
                    .fold([0.0; 4], |a, v| [a[0] + v[0], a[1] + v[1], a[2] + v[2], 0.0]),
            ],
            sum_sq: vec![values.iter().fold([0.0; 4], |a, v| {
                [a[0] + v[0] * v[0], a[1] + v[1] * v[1], a[2] + v[2] * v[2], 0.0]
            })],
        }
    }

    #[test]
    fn mean_and_variance_of_absorbed_batches() {
        let mut r = Reference::new((1, 1), info());
        r.absorb(&frames(&[[1.0, 0.0, 2.0], [3.0, 0.0, 2.0]]));
        r.absorb(&frames(&[[5.0, 0.0, 2.0]]));
        assert_eq!(r.frames, 3);
        assert_eq!(r.samples_per_pixel(), 6);
        assert_eq!(r.mean()[0], [3.0, 0.0, 2.0]);
        // Sample variance of 1, 3, 5 is 4; of the mean, 4 / 3.
        let v = r.variance_of_mean()[0];
        assert!(
            (v[0] - 4.0 / 3.0).abs() < 1e-6 && v[1] == 0.0 && v[2].abs() < 1e-6,
            "{v:?}"
        );
    }

    #[test]
    fn write_then_read_gives_the_sums_back() {
        let dir = std::env::temp_dir().join(format!("lightgraph-ref-{}", std::process::id()));
        let path = dir.join("ref.exr");
        let mut r = Reference::new((2, 1), info());
        let mut a = frames(&[[0.25, 1.0, 7.0], [0.75, 1.5, 9.0]]);
        a.sum.push([10.0, 0.0, 1.0, 0.0]);
        a.sum_sq.push([50.5, 0.0, 0.5, 0.0]);
        r.absorb(&a);
        r.seconds = 1.5;
        r.write(&path).unwrap();
        let back = Reference::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!((back.size, back.frames, back.seconds), ((2, 1), 2, 1.5));
        assert_eq!(back.info, r.info);
        for (a, b) in r.sum.iter().zip(&back.sum).chain(r.sum_sq.iter().zip(&back.sum_sq)) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-6 * a[c].abs().max(1.0), "{a:?} vs {b:?}");
            }
        }
        assert!(back.check_settings(&r.info, &path).is_ok());
        let mut other = r.info.clone();
        other.insert("seed".into(), "9".into());
        let e = back.check_settings(&other, &path).unwrap_err().to_string();
        assert!(
            e.contains("seed is 'seed-value' there, '9' here") && e.contains("ref.exr"),
            "{e}"
        );
    }

    #[test]
    fn a_plain_render_is_not_a_reference() {
        let dir = std::env::temp_dir().join(format!("lightgraph-notref-{}", std::process::id()));
        let path = dir.join("render.exr");
        let image = Image {
            width: 1,
            height: 1,
            frames: 1,
            mean: vec![[1.0; 3]],
            variance: vec![[0.0; 3]],
        };
        crate::output::write_exr(&path, &image, &[]).unwrap();
        let e = Reference::read(&path).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).ok();
        assert!(e.contains("render.exr: not a lightgraph reference"), "{e}");
    }
}
