//! The numerical stress suite: stiff, extreme and degenerate scenes (`scenes/stress/`), each
//! rendered by every radiance estimator and checked against the invariant it must keep, with
//! no NaN, infinite or negative sample and no path left running (loops never capped).
//! `lightgraph stress` runs it at any size; the tests run it small on lavapipe.

pub mod cases;
pub mod stats;

use crate::drive::{Budget, Plan, Stopwatch, drive};
use crate::run::{LoadedScene, Session, SessionOptions, graph_handles_scene, load_graph, load_scene_with};
use anyhow::{Result, bail};
use cases::{Case, Invariant};
use lightgraph_engine::Gpu;
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::BvhKind;
use stats::{Frames, MIN_FRAMES, Z_LIMIT};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::time::Instant;

/// Built-in graphs that do not estimate radiance, so have no stress invariant to keep.
pub const NOT_RADIANCE: [&str; 3] = ["ao", "aov", "trace"];

/// Built-in radiance estimators left out of the stress suite, with the reason: light tracing
/// misses lights seen directly and whatever is seen through a specular surface, so it cannot
/// keep the invariants; NaiveBPT keeps a sample's light vertices in its item, 48 bytes for
/// each of MAX_PATH_LENGTH - 2 slots, too large for the emissive boxes' hundreds of bounces
/// (StreamingBPT keeps both sub-paths' vertices). Photon mapping is consistent but biased at
/// any finite radius, so the unbiased invariants' tolerances do not apply; its merge-radius
/// cases (tiny and huge radii, the radius after 10^4 frames) are in tests/integration/pm.rs;
/// VCM merges too. The Markov chains (PSSMLT, MMLT, Metropolised VCM) splat where they walk, so a pixel's value in a short run is
/// not a per-sample mean that the exact per-pixel invariants can bound, and on llvmpipe a
/// thread that runs a chain's steps over hundreds of bounces passes the driver's loop cap.
pub const INCOMPLETE: [(&str, &str); 12] = [
    (
        "appm",
        "biased at a finite merge radius, as ppm, whose stress cases are in tests/integration/pm.rs",
    ),
    ("bpt-lvc", "new: not yet run through the stress suite"),
    (
        "bpt-naive",
        "items hold MAX_PATH_LENGTH - 2 light vertices: too large for hundreds of bounces",
    ),
    (
        "bpt-streaming",
        "items hold both sub-paths' vertices: too large for hundreds of bounces",
    ),
    ("lt", "light tracing misses directly visible lights and specular paths"),
    (
        "mmlt",
        "Markov chains, as pssmlt: a pixel's value counts the chains' visits, so the exact per-pixel invariants do not hold",
    ),
    (
        "mvcm",
        "Markov chains, as pssmlt, and merges, as vcm: neither the exact per-pixel invariants nor their tolerances apply",
    ),
    (
        "pbpm",
        "biased at a finite merge radius: its stress cases are in tests/integration/pm.rs",
    ),
    (
        "pssmlt",
        "Markov chains: a pixel's value counts the chains' visits, so the exact per-pixel invariants do not hold; on llvmpipe a chain's steps over the emissive boxes' hundreds of bounces pass the loop cap",
    ),
    (
        "ppm",
        "biased at a finite merge radius: its stress cases are in tests/integration/pm.rs",
    ),
    (
        "sppm",
        "biased at a finite merge radius: its stress cases are in tests/integration/pm.rs",
    ),
    (
        "vcm",
        "biased at a finite merge radius: its merge-radius cases are in tests/integration/pm.rs",
    ),
];

/// The built-in graphs that estimate radiance: the estimators every stress scene runs with.
pub fn estimators() -> Vec<String> {
    crate::assets::graph_names()
        .into_iter()
        .filter(|g| !NOT_RADIANCE.contains(&g.as_str()) && !INCOMPLETE.iter().any(|(name, _)| name == g))
        .collect()
}

/// How large a stress run is.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Each case's resolution is multiplied by this.
    pub scale: u32,
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Frames (at least [`MIN_FRAMES`]).
    pub frames: u32,
    /// Seed of the random streams.
    pub seed: u32,
    /// Acceleration structure.
    pub bvh: BvhKind,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            scale: 1,
            spp: 1,
            frames: MIN_FRAMES as u32,
            seed: 1,
            bvh: BvhKind::Cwbvh,
        }
    }
}

/// The result of one case with one estimator.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Stress scene.
    pub scene: String,
    /// Graph.
    pub graph: String,
    /// Whether every check held (true where the graph was left out).
    pub passed: bool,
    /// Why the graph did not render the scene: it does not handle a feature the scene has
    /// (participating media); `None` where it rendered.
    pub left_out: Option<String>,
    /// The invariant's statistic (worst |t| or relative error), in words.
    pub statistic: String,
    /// What failed, if anything.
    pub failures: Vec<String>,
    /// Seconds of rendering, comparison renders included.
    pub seconds: f64,
    /// The mean image, for previews (none when the render failed).
    pub image: Option<crate::run::Image>,
}

/// A render of one scene: its frames and what the counters said.
struct Render {
    frames: Frames,
    rejected: u64,
    loops_capped: u64,
}

/// Runs stress cases, keeping comparison renders for reuse.
pub struct Runner<'g> {
    gpu: &'g Gpu,
    settings: Settings,
    renders: BTreeMap<(String, String, (u32, u32), u32), Frames>,
}

impl<'g> Runner<'g> {
    /// A runner on `gpu` with `settings`.
    pub fn new(gpu: &'g Gpu, settings: Settings) -> Result<Runner<'g>> {
        if (settings.frames as usize) < MIN_FRAMES {
            bail!("a stress run needs at least {MIN_FRAMES} frames for its statistics");
        }
        Ok(Runner {
            gpu,
            settings,
            renders: BTreeMap::new(),
        })
    }

    fn render(&self, loaded: &LoadedScene, graph: &str, size: (u32, u32), seed: u32) -> Result<Render> {
        let graph = load_graph(graph)?;
        let options = SessionOptions {
            width: size.0,
            height: size.1,
            samples_per_frame: self.settings.spp,
            seed,
            constants: BTreeMap::new(),
            layout: Default::default(),
        };
        let mut session = Session::new(self.gpu, &graph, &graph.default_layout.clone(), loaded, options)?;
        let mut frames = Vec::with_capacity(self.settings.frames as usize);
        // Every group of frames the GPU renders as one taken apart: the invariants' samples.
        let mut take = |session: &mut Session, _: &mut Stopwatch| -> Result<()> {
            let taken = session.take_accumulation()?;
            frames.push(taken.sum.iter().map(|s| [s[0], s[1], s[2]]).collect());
            Ok(())
        };
        let at_once = session.frames_at_once() as u64;
        let plan = Plan::new(Budget::Frames(self.settings.frames as u64 * at_once)).in_steps_of(at_once);
        drive(&mut session, plan, &mut Stopwatch::start(), &mut [&mut take])?.whole("the stress case")?;
        Ok(Render {
            frames: Frames { size, frames },
            rejected: session.counters.get("samples_rejected").copied().unwrap_or(0),
            loops_capped: session.loops_capped,
        })
    }

    /// Frames of a comparison scene, rendered once per (scene, graph, size, seed).
    fn comparison(&mut self, scene: &str, graph: &str, size: (u32, u32), seed: u32) -> Result<Frames> {
        let key = (scene.to_string(), graph.to_string(), size, seed);
        if !self.renders.contains_key(&key) {
            let r = self.render(&load_scene_with(scene, self.settings.bvh)?, graph, size, seed)?;
            if r.rejected > 0 || r.loops_capped > 0 {
                bail!(
                    "the comparison scene {scene} itself had {} rejected samples and {} capped loops",
                    r.rejected,
                    r.loops_capped
                );
            }
            self.renders.insert(key.clone(), r.frames);
        }
        Ok(self.renders[&key].clone())
    }

    /// Renders `case` with `graph` and checks it; an error (a scene that does not load, a
    /// failed render) is a failed outcome.
    pub fn run(&mut self, case: &Case, graph: &str) -> Outcome {
        let start = Instant::now();
        self.try_run(case, graph).unwrap_or_else(|e| Outcome {
            scene: case.scene.to_string(),
            graph: graph.to_string(),
            passed: false,
            left_out: None,
            statistic: "error".to_string(),
            failures: vec![format!("{e:#}")],
            seconds: start.elapsed().as_secs_f64(),
            image: None,
        })
    }

    fn try_run(&mut self, case: &Case, graph: &str) -> Result<Outcome> {
        let start = Instant::now();
        let s = self.settings;
        let size = (case.resolution.0 * s.scale, case.resolution.1 * s.scale);
        let loaded = load_scene_with(case.scene, s.bvh)?;
        if let Err(why) = graph_handles_scene(&load_graph(graph)?, &loaded) {
            return Ok(Outcome {
                scene: case.scene.to_string(),
                graph: graph.to_string(),
                passed: true,
                left_out: Some(why),
                statistic: "left out".to_string(),
                failures: Vec::new(),
                seconds: start.elapsed().as_secs_f64(),
                image: None,
            });
        }
        let render = self.render(&loaded, graph, size, s.seed)?;
        let mut failures = Vec::new();
        if render.rejected > 0 {
            failures.push(format!("{} NaN, infinite or negative samples", render.rejected));
        }
        if render.loops_capped > 0 {
            failures.push(format!("{} loops stopped by the iteration cap", render.loops_capped));
        }
        let mean = render.frames.mean();
        if let Some(i) = mean.iter().position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0)) {
            failures.push(format!("pixel {i} is {:?}", mean[i]));
        }
        let scene = &loaded.scene;
        let statistic = match case.invariant {
            Invariant::Expect(e) => {
                let camera = CompiledScene::camera(scene, size.0, size.1);
                let expected = e.expected(scene, &camera);
                check_expected(&render.frames, &expected, &mut failures)
            }
            Invariant::SameAs(other) => {
                // An independent seed, so the two renders' errors are independent.
                let base = self.comparison(other, graph, size, s.seed.wrapping_add(7919))?;
                check_same(&render.frames, &base, &mut failures)
            }
            Invariant::ScaledCopyOf(other, factor) => {
                let base = self.comparison(other, graph, size, s.seed)?;
                check_scaled(&mean, &base.mean(), factor, &mut failures)
            }
            Invariant::Background(rel) => check_exact(&mean, cases::background(scene), rel, &mut failures),
            Invariant::Furnace(rate) => {
                let samples = (s.spp * s.frames) as f64;
                check_furnace(&mean, cases::background(scene), samples, rate, &mut failures)
            }
            Invariant::Enclosed(rate) => {
                let samples = (s.spp * s.frames) as f64;
                check_enclosed(&mean, cases::background(scene), samples, rate, &mut failures)
            }
        };
        let image = crate::run::Image {
            width: size.0,
            height: size.1,
            frames: s.frames,
            mean: mean.iter().map(|p| p.map(|v| v as f32)).collect(),
            variance: vec![[0.0; 3]; mean.len()],
        };
        Ok(Outcome {
            scene: case.scene.to_string(),
            graph: graph.to_string(),
            passed: failures.is_empty(),
            left_out: None,
            statistic,
            failures,
            seconds: start.elapsed().as_secs_f64(),
            image: Some(image),
        })
    }
}

/// Region means against expected intervals: the worst |t| by which a region's mean lies
/// outside its interval.
fn check_expected(frames: &Frames, expected: &cases::Expected, failures: &mut Vec<String>) -> String {
    let mask: Vec<bool> = expected.iter().map(Option::is_some).collect();
    let regions = frames.blocks(4, &mask);
    let mut worst = (0.0f64, String::new());
    for weight in &regions {
        let stat = frames.region(weight);
        let total: f64 = weight.iter().sum();
        for c in 0..3 {
            let bound = |hi: bool| {
                expected
                    .iter()
                    .zip(weight)
                    .filter_map(|(e, w)| e.map(|(l, h)| w * if hi { h[c] } else { l[c] }))
                    .sum::<f64>()
                    / total
            };
            let (lo, hi) = (bound(false), bound(true));
            let outside = (lo - stat.mean[c]).max(stat.mean[c] - hi).max(0.0);
            let t = if outside == 0.0 {
                0.0
            } else {
                outside / stat.se[c].max(1e-12 * hi.abs())
            };
            if t > worst.0 {
                worst = (
                    t,
                    format!(
                        "a region's mean {:.6e} lies outside [{lo:.6e}, {hi:.6e}] by {t:.1} standard errors",
                        stat.mean[c]
                    ),
                );
            }
        }
    }
    if worst.0 > Z_LIMIT {
        failures.push(worst.1);
    }
    format!("worst |t| {:.2} over {} regions", worst.0, regions.len())
}

/// Two renders region by region: the worst |t| of their difference.
fn check_same(a: &Frames, b: &Frames, failures: &mut Vec<String>) -> String {
    let all = vec![true; a.frames[0].len()];
    let regions = a.blocks(4, &all);
    let mut worst = (0.0f64, String::new());
    for weight in &regions {
        let (sa, sb) = (a.region(weight), b.region(weight));
        for c in 0..3 {
            let se = (sa.se[c].powi(2) + sb.se[c].powi(2)).sqrt();
            let diff = (sa.mean[c] - sb.mean[c]).abs();
            let t = if diff == 0.0 {
                0.0
            } else {
                diff / se.max(1e-12 * sb.mean[c].abs())
            };
            if t > worst.0 {
                worst = (
                    t,
                    format!(
                        "a region's mean is {:.6e} here, {:.6e} in the comparison scene: {t:.1} standard errors apart",
                        sa.mean[c], sb.mean[c]
                    ),
                );
            }
        }
    }
    if worst.0 > Z_LIMIT {
        failures.push(worst.1);
    }
    format!("worst |t| {:.2} over {} regions", worst.0, regions.len())
}

/// A render against a comparison render times `factor`, pixel by pixel: relative error up to
/// 1e-3 of the pixel (float rounding and the order of atomic additions), with a floor of 1e-6
/// of the image's mean for pixels near zero.
fn check_scaled(image: &[[f64; 3]], base: &[[f64; 3]], factor: f64, failures: &mut Vec<String>) -> String {
    let scale = base.iter().flatten().map(|v| v.abs()).sum::<f64>() / (3 * base.len()).max(1) as f64 * factor;
    let mut worst = (0.0f64, 0usize);
    for (i, (x, b)) in image.iter().zip(base).enumerate() {
        for c in 0..3 {
            let want = b[c] * factor;
            let rel = (x[c] - want).abs() / want.abs().max(1e-3 * scale);
            if rel > worst.0 {
                worst = (rel, i);
            }
        }
    }
    if worst.0 > 1e-3 || scale == 0.0 {
        let i = worst.1;
        failures.push(format!(
            "pixel {i} is {:?}, the comparison scene's times {factor:e} is {:?} (relative error {:.2e})",
            image[i],
            base[i].map(|v| v * factor),
            worst.0
        ));
    }
    format!("worst relative error {:.2e}", worst.0)
}

/// Every pixel exactly `value`, to a relative tolerance.
fn check_exact(image: &[[f64; 3]], value: [f64; 3], rel: f64, failures: &mut Vec<String>) -> String {
    let mut worst = (0.0f64, 0usize);
    for (i, p) in image.iter().enumerate() {
        for c in 0..3 {
            let err = (p[c] - value[c]).abs();
            if err > worst.0 {
                worst = (err, i);
            }
        }
    }
    let limit = rel * value.iter().fold(0.0f64, |a, &b| a.max(b));
    if worst.0 > limit {
        failures.push(format!("pixel {} is {:?}, not {value:?}", worst.1, image[worst.1]));
    }
    format!("worst absolute error {:.2e}", worst.0)
}

/// Samples per pixel that went wrong, summed over an image of `samples` per pixel: `share`
/// gives each pixel's wrong fraction. At most `rate` of all samples may be wrong.
fn check_count(
    image: &[[f64; 3]],
    samples: f64,
    rate: f64,
    share: impl Fn(&[f64; 3]) -> f64,
    what: &str,
    failures: &mut Vec<String>,
) -> String {
    let count = 0.0 + image.iter().map(|p| share(p) * samples).sum::<f64>();
    let total = samples * image.len() as f64;
    let allowed = (rate * total).floor();
    if count.round() > allowed {
        failures.push(format!(
            "{count:.0} of {total:.0} samples {what} (at most {allowed:.0} may)"
        ));
    }
    format!("{count:.0} samples of {total:.0} {what}")
}

/// A white furnace with a lossless object: no pixel above the environment by more than
/// rounding (1e-5), and the pixels below it by more than rounding add up to at most `rate` of
/// all samples lost.
fn check_furnace(
    image: &[[f64; 3]],
    environment: [f64; 3],
    samples: f64,
    rate: f64,
    failures: &mut Vec<String>,
) -> String {
    let l = environment[1];
    let brightest = image.iter().map(|p| p[1]).fold(0.0f64, f64::max);
    if brightest > l * (1.0 + 1e-5) {
        failures.push(format!("a pixel is {brightest}, brighter than the environment's {l}"));
    }
    let lost = |p: &[f64; 3]| Some((l - p[1]) / l).filter(|&d| d > 1e-5).unwrap_or(0.0);
    let stat = check_count(image, samples, rate, lost, "were lost", failures);
    format!("{stat}; brightest {brightest:.7}")
}

/// An enclosure's image: each pixel is (leaked samples / samples) x the environment, so the
/// image counts the rays that slipped through; at most `rate` of all samples may have.
fn check_enclosed(
    image: &[[f64; 3]],
    environment: [f64; 3],
    samples: f64,
    rate: f64,
    failures: &mut Vec<String>,
) -> String {
    let leaked = |p: &[f64; 3]| p[1] / environment[1];
    check_count(
        image,
        samples,
        rate,
        leaked,
        "saw the environment through the walls",
        failures,
    )
}

/// A Markdown table of outcomes.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut s = String::from("| scene | estimator | result | statistic | seconds |\n|---|---|---|---|---:|\n");
    for o in outcomes {
        let result = if let Some(why) = &o.left_out {
            format!("left out: {why}")
        } else if o.passed {
            "ok".to_string()
        } else {
            format!("**FAILED**: {}", o.failures.join("; "))
        };
        let _ = writeln!(
            s,
            "| {} | {} | {result} | {} | {:.2} |",
            o.scene, o.graph, o.statistic, o.seconds
        );
    }
    s
}
