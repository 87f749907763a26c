//! Films: progressive renders whose sums are kept on the host in f64, stored as EXR with the
//! mean radiance (and the f32 remainder of its f64 value), its per-pixel variance, the
//! settings that made it and the frame indices it holds. `reference` writes them and resumes
//! them (more samples added with the same settings), `render` writes one, and `merge` adds
//! films of the same settings over disjoint frame ranges (shards of one run) into one;
//! [`crate::reference`] renders a reference.

use crate::output::{ExrFile, read_exr, write_channels};
use crate::run::{Accumulation, Image, RunOptions, SessionOptions};
use anyhow::{Result, anyhow, bail};
use lightgraph_engine::{ConstValue, Graph};
use std::collections::BTreeMap;
use std::path::Path;

/// Settings that must be the same for every sample of a reference: the estimate they define.
pub const SETTINGS: [&str; 5] = ["scene", "graph", "samples_per_frame", "seed", "constants"];

/// Settings that must be the same too, but that a film may lack: `measured`, the graph's
/// measured constants (LVC-BPT's average light sub-path length), which choose the estimator's
/// weights but not the image it converges to (so `compare` does not ask a reference for them).
pub const OPTIONAL_SETTINGS: [&str; 1] = ["measured"];

/// The frames a film rendered or resumed holds at the end when given neither frames nor a
/// time (`--frames`, Python's `frames=`).
pub const DEFAULT_FRAMES: u32 = 64;

/// How a front end names the options of a run's length in its messages: the command line's
/// `--frames 256`, Python's `frames=256`.
pub struct LengthOptions {
    /// The option of the frames the film holds at the end.
    pub frames: &'static str,
    /// The option of the time to render for.
    pub time: &'static str,
    /// The option of the film resumed.
    pub resume: &'static str,
    /// What joins an option to its value: " " on the command line, "=" in Python.
    pub joiner: &'static str,
}

/// The command line's names: `--frames 256`.
pub const CLI_LENGTH_OPTIONS: LengthOptions = LengthOptions {
    frames: "--frames",
    time: "--time",
    resume: "--resume",
    joiner: " ",
};

/// A film (a reference image) being accumulated in f64: per pixel the sum of the frames'
/// estimates and of their squares, and the frame indices summed.
#[derive(Debug, Clone)]
pub struct Film {
    /// Width and height.
    pub size: (u32, u32),
    /// Frames accumulated.
    pub frames: u64,
    /// The frame indices accumulated: sorted, disjoint, half-open ranges, adjacent ones joined.
    pub ranges: Vec<(u64, u64)>,
    /// Render seconds spent on it, over every run that added to it.
    pub seconds: f64,
    /// The [`SETTINGS`] and descriptive entries (layout, adapter) as text.
    pub info: BTreeMap<String, String>,
    /// Further layers written as they are (`render --aov`'s feature buffers): channel name
    /// (`layer.channel`) and one value per pixel. Not read back, not merged.
    pub layers: Vec<(String, Vec<f32>)>,
    pub(crate) sum: Vec<[f64; 3]>,
    pub(crate) sum_sq: Vec<[f64; 3]>,
}

impl Film {
    /// An empty reference of `size` with the settings and description in `info`.
    pub fn new(size: (u32, u32), info: BTreeMap<String, String>) -> Film {
        let n = size.0 as usize * size.1 as usize;
        Film {
            size,
            frames: 0,
            ranges: Vec::new(),
            seconds: 0.0,
            info,
            layers: Vec::new(),
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
        }
    }

    /// Adds the frames of a GPU accumulation (see
    /// [`crate::run::Session::take_accumulation`]); an error, and nothing added, if it
    /// holds frame indices the film has already.
    pub fn absorb(&mut self, taken: &Accumulation) -> Result<()> {
        self.ranges = join_ranges(self.ranges.iter().chain(&taken.ranges).copied().collect())?;
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
        Ok(())
    }

    /// Sets the frame indices accumulated to `ranges` (any order; they must not overlap) and
    /// the frame count to their total.
    pub fn set_ranges(&mut self, ranges: Vec<(u64, u64)>) -> Result<()> {
        self.ranges = join_ranges(ranges)?;
        self.frames = self.ranges.iter().map(|r| r.1 - r.0).sum();
        Ok(())
    }

    /// The frame index after the last one accumulated (0 for an empty film): where a resumed
    /// run starts.
    pub fn end_frame(&self) -> u64 {
        self.ranges.last().map_or(0, |r| r.1)
    }

    /// The first frame index of a run that adds to this film: `given` (`--first-frame`), which
    /// must come after every frame the film holds, else the end of those frames.
    pub fn next_first_frame(&self, given: Option<u32>) -> Result<u32> {
        let end = self.end_frame();
        let first = given.map_or(end, u64::from);
        if first < end {
            bail!("--first-frame {first} is inside the frames the film holds (up to {end}); give {end} or more");
        }
        u32::try_from(first)
            .map_err(|_| anyhow!("the film ends at frame {end}, past 2^32; start another with a new seed"))
    }

    /// The frames a resumed run of `total` frames in all (its frames option, `options` naming
    /// it) still has to render into this film, read from `path`; none left is an error that
    /// names the file and says what to give.
    pub fn frames_left(&self, total: u32, path: &Path, options: &LengthOptions) -> Result<u32> {
        let (
            held,
            LengthOptions {
                frames,
                time,
                resume,
                joiner,
            },
        ) = (self.frames, options);
        match u64::from(total).checked_sub(held) {
            Some(left) if left > 0 => Ok(left as u32),
            _ => bail!(
                "{}: the film holds {held} frames already, and {frames}{joiner}{total} asks for {total} in all (with {resume}, {frames} counts the film's frames too, {DEFAULT_FRAMES} when not given): give a larger {frames}, or {time} to render for a while more",
                path.display()
            ),
        }
    }

    /// Adds the film `other` (read from `path`), made with the same settings over frames this
    /// one does not hold: the sums, frames and seconds add up, the layouts and adapters are
    /// listed once each, and numeric statistics (`rays`, `rejected_samples`) add up.
    pub fn merge(&mut self, other: &Film, path: &Path) -> Result<()> {
        other.check_settings(&self.info, path)?;
        if other.size != self.size {
            bail!(
                "{}: the film is {}x{}, the others {}x{}",
                path.display(),
                other.size.0,
                other.size.1,
                self.size.0,
                self.size.1
            );
        }
        self.ranges = join_ranges(self.ranges.iter().chain(&other.ranges).copied().collect())
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        for (a, b) in self
            .sum
            .iter_mut()
            .zip(&other.sum)
            .chain(self.sum_sq.iter_mut().zip(&other.sum_sq))
        {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.frames += other.frames;
        self.seconds += other.seconds;
        for key in ["layout", "adapter"] {
            let mut items: Vec<String> = Vec::new();
            for list in [self.info.get(key), other.info.get(key)].into_iter().flatten() {
                for item in list.split(", ").filter(|s| !s.is_empty()) {
                    if !items.iter().any(|i| i == item) {
                        items.push(item.to_string());
                    }
                }
            }
            self.info.insert(key.to_string(), items.join(", "));
        }
        for key in ["rays", "rejected_samples"] {
            let sum = [self.info.get(key), other.info.get(key)].map(|v| v.and_then(|v| v.parse::<u64>().ok()));
            match sum {
                [Some(a), Some(b)] => self.info.insert(key.to_string(), (a + b).to_string()),
                _ => self.info.remove(key),
            };
        }
        Ok(())
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

    /// Writes the film as an EXR: channels R, G, B (mean radiance), residual.R, residual.G,
    /// residual.B (the f32 remainder of the f64 mean, so that shards merge to float rounding
    /// of f64) and variance.R, variance.G, variance.B (variance of the mean), with the
    /// settings, frames, frame ranges, samples per pixel and seconds as `lightgraph.*`
    /// attributes, and `kind` (what wrote it: reference, render or merge).
    pub fn write(&self, path: &Path, kind: &str) -> Result<()> {
        let n = self.frames.max(1) as f64;
        let var = self.variance_of_mean();
        let channel = |v: &[[f32; 3]], c: usize| v.iter().map(|p| p[c]).collect::<Vec<f32>>();
        let mut channels = Vec::new();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let mean: Vec<f64> = self.sum.iter().map(|s| s[c] / n).collect();
            channels.push((name.to_string(), mean.iter().map(|&m| m as f32).collect()));
            channels.push((
                format!("residual.{name}"),
                mean.iter().map(|&m| (m - m as f32 as f64) as f32).collect(),
            ));
            channels.push((format!("variance.{name}"), channel(&var, c)));
        }
        channels.extend(self.layers.iter().cloned());
        let mut meta: Vec<(&str, String)> = self.info.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
        meta.push(("kind", kind.into()));
        meta.push(("frames", self.frames.to_string()));
        meta.push((
            "frame_ranges",
            self.ranges.iter().map(|r| range_text(*r)).collect::<Vec<_>>().join(","),
        ));
        meta.push(("samples_per_pixel", self.samples_per_pixel().to_string()));
        meta.push(("seconds", format!("{:.3}", self.seconds)));
        write_channels(path, self.size, channels, &meta)
    }

    /// Reads a film written by [`Film::write`]: its mean and residual give the sums back
    /// to about 1e-14 relative (films written before the residual, to 1e-7), its variance the
    /// sums of squares to about 1e-7, far below any film's noise. A film without frame ranges
    /// holds frames 0 .. frames.
    pub fn read(path: &Path) -> Result<Film> {
        let file = read_exr(path)?;
        let frames = number(&file, path, "frames")?;
        let seconds = number(&file, path, "seconds")?;
        let mut info = file.metadata.clone();
        for key in ["kind", "frames", "frame_ranges", "samples_per_pixel", "seconds"] {
            info.remove(key);
        }
        if let Some(missing) = SETTINGS.iter().find(|k| !info.contains_key(**k)) {
            bail!(
                "{}: not a lightgraph reference (no '{missing}' attribute)",
                path.display()
            );
        }
        let mut reference = Film::new(file.size, info);
        reference.seconds = seconds;
        reference.ranges = match file.metadata.get("frame_ranges") {
            Some(text) => parse_ranges(text).ok_or_else(|| {
                anyhow!(
                    "{}: invalid frame ranges '{text}' (expected FIRST..END,...)",
                    path.display()
                )
            })?,
            None if frames > 0.0 => vec![(0, frames as u64)],
            None => Vec::new(),
        };
        reference.frames = reference.ranges.iter().map(|r| r.1 - r.0).sum();
        if reference.frames != frames as u64 {
            bail!(
                "{}: its frame ranges hold {} frames, its 'frames' says {frames}",
                path.display(),
                reference.frames
            );
        }
        let n = frames;
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let mean = file.channel(name, path)?;
            let var = file.channel(&format!("variance.{name}"), path)?;
            let residual = file.channels.get(&format!("residual.{name}"));
            for (i, (&m, &v)) in mean.iter().zip(var).enumerate() {
                let m = m as f64 + residual.map_or(0.0, |r| r[i] as f64);
                let v = v as f64;
                reference.sum[i][c] = m * n;
                // Inverse of variance_of_mean: sum_sq / n = v (n - 1) + m².
                reference.sum_sq[i][c] = n * (v * (n - 1.0).max(0.0) + m * m);
            }
        }
        Ok(reference)
    }

    /// Checks that a reference has the image size of the render compared with it.
    pub fn check_size(&self, path: &Path, size: (u32, u32)) -> Result<()> {
        if self.size != size {
            bail!(
                "{}: the reference is {}x{}, the render {}x{}; pass --res {}x{} or make a reference at this size",
                path.display(),
                self.size.0,
                self.size.1,
                size.0,
                size.1,
                self.size.0,
                self.size.1
            );
        }
        Ok(())
    }

    /// Checks that the settings in `info` are those of this reference, naming each that
    /// differs.
    pub fn check_settings(&self, info: &BTreeMap<String, String>, path: &Path) -> Result<()> {
        let differ: Vec<String> = SETTINGS
            .iter()
            .chain(&OPTIONAL_SETTINGS)
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
                "{}: the film was made with other settings, so samples cannot be added to it: {}",
                path.display(),
                differ.join("; ")
            );
        }
        Ok(())
    }
}

/// The settings a film records and `merge` checks ([`SETTINGS`], and
/// `measured`, the graph's measured constants, where it has any).
pub fn film_settings(scene: &str, graph: &Graph, opts: &SessionOptions) -> BTreeMap<String, String> {
    let (measured, constants): (BTreeMap<_, _>, BTreeMap<_, _>) = opts
        .constants
        .clone()
        .into_iter()
        .partition(|(name, _)| graph.measured.contains_key(name));
    let mut settings: BTreeMap<String, String> = [
        ("scene", scene.to_string()),
        ("graph", graph.name.clone()),
        ("samples_per_frame", opts.samples_per_frame.to_string()),
        ("seed", opts.seed.to_string()),
        ("constants", constants_text(&constants)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    if !measured.is_empty() {
        settings.insert("measured".to_string(), constants_text(&measured));
    }
    settings
}

/// The constant overrides as `NAME=VALUE` words (the inverse of the CLI's `--set` parsing).
pub fn constants_text(constants: &BTreeMap<String, ConstValue>) -> String {
    let words: Vec<String> = constants
        .iter()
        .map(|(k, v)| match v {
            ConstValue::U32(x) => format!("{k}={x}"),
            ConstValue::I32(x) => format!("{k}={x}"),
            ConstValue::F32(x) => format!("{k}={x:?}"),
            ConstValue::Bool(x) => format!("{k}={x}"),
        })
        .collect();
    words.join(" ")
}

/// `ranges` sorted, adjacent ones joined; an error naming two that overlap.
fn join_ranges(mut ranges: Vec<(u64, u64)>) -> Result<Vec<(u64, u64)>> {
    ranges.sort_unstable();
    let mut joined: Vec<(u64, u64)> = Vec::new();
    for r in ranges.into_iter().filter(|r| r.0 < r.1) {
        match joined.last_mut() {
            Some(last) if r.0 < last.1 => {
                bail!(
                    "frames {} overlap frames {} already in the film",
                    range_text(r),
                    range_text(*last)
                )
            }
            Some(last) if last.1 == r.0 => last.1 = r.1,
            _ => joined.push(r),
        }
    }
    Ok(joined)
}

/// A frame range as text: FIRST..END (END excluded).
fn range_text(r: (u64, u64)) -> String {
    format!("{}..{}", r.0, r.1)
}

/// Parses FIRST..END,... into sorted, disjoint, joined ranges; None if malformed or
/// overlapping.
fn parse_ranges(text: &str) -> Option<Vec<(u64, u64)>> {
    let mut ranges = Vec::new();
    for item in text.split(',').filter(|s| !s.trim().is_empty()) {
        let (a, b) = item.trim().split_once("..")?;
        let (a, b) = (a.parse::<u64>().ok()?, b.parse::<u64>().ok()?);
        if a >= b {
            return None;
        }
        ranges.push((a, b));
    }
    join_ranges(ranges).ok()
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

/// Run options filled from a film: the settings a front end did not give (the film is a leaf
/// the runs depend on, not the other way round).
impl RunOptions {
    /// Fills the scene, resolution and constants not given with those of `reference`.
    pub fn from_reference(&mut self, reference: &Film) {
        let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
        self.scene.get_or_insert_with(|| info("scene"));
        self.res.get_or_insert(reference.size);
        if self.sets.is_empty() && self.max_path_length.is_none() {
            self.sets = info("constants").split_whitespace().map(String::from).collect();
        }
    }

    /// Fills the settings a resumed film has and these options, `graph` and `seed` do not
    /// give: scene, graph, resolution, samples per frame, seed (default `default_seed`) and
    /// constants (the measured ones too, so the resumed run renders the film's estimator).
    /// Those given must match the film's: [`Film::check_settings`] checks them.
    pub fn from_film(&mut self, graph: &mut Option<String>, seed: &mut Option<u32>, default_seed: u32, film: &Film) {
        let info = |k: &str| film.info.get(k).cloned().unwrap_or_default();
        self.scene.get_or_insert_with(|| info("scene"));
        graph.get_or_insert_with(|| info("graph"));
        self.res.get_or_insert(film.size);
        self.spp
            .get_or_insert_with(|| info("samples_per_frame").parse().unwrap_or(1));
        seed.get_or_insert_with(|| info("seed").parse().unwrap_or(default_seed));
        if self.sets.is_empty() && self.max_path_length.is_none() {
            let words = format!("{} {}", info("constants"), info("measured"));
            self.sets = words.split_whitespace().map(String::from).collect();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frames_left_are_the_total_less_the_films() {
        let path = Path::new("film.exr");
        let mut film = Film::new((1, 1), BTreeMap::new());
        film.frames = 64;
        assert_eq!(film.frames_left(256, path, &CLI_LENGTH_OPTIONS).unwrap(), 192);
        for held in [256, 300] {
            film.frames = held;
            let err = film
                .frames_left(256, path, &CLI_LENGTH_OPTIONS)
                .unwrap_err()
                .to_string();
            assert!(
                err.starts_with(&format!("film.exr: the film holds {held} frames"))
                    && err.contains("--frames 256 asks for 256")
                    && err.contains("--time"),
                "{err}"
            );
        }
    }

    fn info() -> BTreeMap<String, String> {
        SETTINGS
            .iter()
            .chain(&OPTIONAL_SETTINGS)
            .map(|k| (k.to_string(), format!("{k}-value")))
            .chain([("samples_per_frame".to_string(), "2".to_string())])
            .collect()
    }

    /// One pixel's frames `values`, the first of them frame index `first`.
    fn frames_from(first: u32, values: &[[f32; 3]]) -> Accumulation {
        Accumulation {
            ranges: vec![(first as u64, first as u64 + values.len() as u64)],
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

    fn frames(values: &[[f32; 3]]) -> Accumulation {
        frames_from(0, values)
    }

    #[test]
    fn mean_and_variance_of_absorbed_batches() {
        let mut r = Film::new((1, 1), info());
        r.absorb(&frames(&[[1.0, 0.0, 2.0], [3.0, 0.0, 2.0]])).unwrap();
        r.absorb(&frames_from(2, &[[5.0, 0.0, 2.0]])).unwrap();
        assert_eq!((r.frames, r.ranges.clone(), r.end_frame()), (3, vec![(0, 3)], 3));
        let e = r.absorb(&frames_from(2, &[[5.0, 0.0, 2.0]])).unwrap_err().to_string();
        assert!(e.contains("frames 2..3 overlap frames 0..3"), "{e}");
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
        let mut r = Film::new((2, 1), info());
        let mut a = frames(&[[0.25, 1.0, 7.0], [0.75, 1.5, 9.0]]);
        a.sum.push([10.0, 0.0, 1.0, 0.0]);
        a.sum_sq.push([50.5, 0.0, 0.5, 0.0]);
        r.absorb(&a).unwrap();
        r.seconds = 1.5;
        r.write(&path, "reference").unwrap();
        let back = Film::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!((back.size, back.frames, back.seconds), ((2, 1), 2, 1.5));
        assert_eq!(back.ranges, vec![(0, 2)]);
        assert_eq!(back.info, r.info);
        // The mean with its residual gives the sums to f64 rounding; the squares to f32's.
        for (a, b) in r.sum.iter().zip(&back.sum) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-13 * a[c].abs().max(1.0), "{a:?} vs {b:?}");
            }
        }
        for (a, b) in r.sum_sq.iter().zip(&back.sum_sq) {
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

    /// A 1x1 film of `info` holding frames `first ..` with the values `v`.
    fn film(info: BTreeMap<String, String>, first: u32, v: &[[f32; 3]]) -> Film {
        let mut r = Film::new((1, 1), info);
        r.absorb(&frames_from(first, v)).unwrap();
        r
    }

    #[test]
    fn films_of_disjoint_frames_merge_into_their_union() {
        let path = Path::new("b.exr");
        let mut a = film(info(), 0, &[[1.0, 2.0, 3.0], [3.0, 2.0, 1.0]]);
        a.info.insert("layout".into(), "L1".into());
        a.info.insert("rays".into(), "10".into());
        let mut b = film(info(), 4, &[[5.0, 2.0, 2.0]]);
        b.info.insert("layout".into(), "L2".into());
        b.info.insert("rays".into(), "5".into());
        a.merge(&b, path).unwrap();
        assert_eq!((a.frames, a.ranges.clone()), (3, vec![(0, 2), (4, 5)]));
        assert_eq!(a.mean()[0], [3.0, 2.0, 2.0]);
        assert_eq!((a.info["layout"].as_str(), a.info["rays"].as_str()), ("L1, L2", "15"));
        // Filling the gap joins the ranges.
        a.merge(&film(info(), 2, &[[0.0; 3], [0.0; 3]]), path).unwrap();
        assert_eq!(a.ranges, vec![(0, 5)]);
    }

    #[test]
    fn films_that_do_not_match_are_refused_each_with_its_reason() {
        let path = Path::new("shard-1.exr");
        let a = film(info(), 0, &[[1.0; 3]]);
        // Each setting that defines the estimate, changed alone.
        for key in SETTINGS.into_iter().chain(OPTIONAL_SETTINGS) {
            let mut other = info();
            other.insert(key.to_string(), "other".into());
            let e = a
                .clone()
                .merge(&film(other, 1, &[[1.0; 3]]), path)
                .unwrap_err()
                .to_string();
            let value = &info()[key];
            let expected = format!("{key} is 'other' there, '{value}' here");
            assert!(e.contains("shard-1.exr") && e.contains(&expected), "{e}");
        }
        // A film that measured nothing against one that did.
        let mut unmeasured = info();
        unmeasured.remove("measured");
        let e = a
            .clone()
            .merge(&film(unmeasured, 1, &[[1.0; 3]]), path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("measured is '' there, 'measured-value' here"), "{e}");
        let mut wide = film(info(), 1, &[[1.0; 3]]);
        wide.size = (2, 1);
        for (b, expected) in [
            (wide, "the film is 2x1, the others 1x1"),
            (film(info(), 0, &[[1.0; 3]]), "frames 0..1 overlap frames 0..1"),
        ] {
            let e = a.clone().merge(&b, path).unwrap_err().to_string();
            assert!(e.contains("shard-1.exr") && e.contains(expected), "{e}");
        }
    }

    #[test]
    fn frame_ranges_parse_and_malformed_ones_are_refused() {
        assert_eq!(parse_ranges("4..6,0..2,2..3"), Some(vec![(0, 3), (4, 6)]));
        assert_eq!(parse_ranges(""), Some(vec![]));
        for bad in ["0..", "3..1", "0..2,1..3", "x..2", "5"] {
            assert_eq!(parse_ranges(bad), None, "{bad}");
        }
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
        let e = Film::read(&path).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).ok();
        assert!(e.contains("render.exr: not a lightgraph reference"), "{e}");
    }
}
