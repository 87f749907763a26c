//! Error against time: estimators and layouts render one scene for the same wall-clock
//! budget, their error against a reference is sampled at log-spaced times with the clock
//! paused, and the curves, a log-log plot, the final images and a summary of
//! time-to-target-error speed-ups (the paper's Figure 10 and Table III) are written. A
//! signal ends the run in flight at its next batch of frames and drops it; the finished
//! runs are kept ([`resume`]).

pub mod curve;
pub mod html;
pub mod render;
pub mod resume;

pub use curve::{convergence_slope, tail_noise, time_to_error};

use crate::drive::{Budget, Ended, Observer, Plan, Stopwatch, drive};
use crate::film::Film;
use crate::interrupt::Interrupted;
use crate::metrics::{ImageError, image_error};
use crate::plot::{Axes, Series, line_plot};
use crate::run::{Image, Run, Session, load_graph, named_layout, parse_sets};
use anyhow::{Context, Result, bail};
use lightgraph_engine::Gpu;
use std::fmt::Write;
use std::path::Path;
use std::time::{Duration, Instant};

/// One estimator in one layout to compare: `graph:layout`, or `graph` for its default layout,
/// each optionally followed by `@NAME=VALUE` settings of its own constants (e.g.
/// `ppm:PPMsk@PM_STRUCTURE=3`), which the reference need not share.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimatorSpec {
    /// Graph name or `.ron` path.
    pub graph: String,
    /// Layout name; the graph's default when absent.
    pub layout: Option<String>,
    /// The run's own constant settings, `NAME=VALUE`.
    pub sets: Vec<String>,
}

impl EstimatorSpec {
    /// Parses a comma-separated list of `graph[:layout][@NAME=VALUE...]`.
    pub fn parse_list(list: &str) -> Result<Vec<EstimatorSpec>> {
        let runs: Vec<EstimatorSpec> = list
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| {
                let mut parts = s.split('@').map(str::trim);
                let run = parts.next().unwrap_or_default();
                let sets = parts.map(str::to_string).collect();
                let (graph, layout) = match run.rsplit_once(':') {
                    Some((g, l)) if !l.is_empty() && !l.contains(['/', '\\']) => (g, Some(l.to_string())),
                    _ => (run, None),
                };
                EstimatorSpec {
                    graph: graph.to_string(),
                    layout,
                    sets,
                }
            })
            .collect();
        if runs.is_empty() {
            bail!("--runs names no run; give graph:layout pairs, e.g. pt:NaivePTsk,pt:RegenerationPTsk");
        }
        Ok(runs)
    }
}

/// The inverse of [`EstimatorSpec::parse_list`] for one run: `graph[:layout][@NAME=VALUE...]`.
impl std::fmt::Display for EstimatorSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.graph)?;
        if let Some(layout) = &self.layout {
            write!(f, ":{layout}")?;
        }
        self.sets.iter().try_for_each(|set| write!(f, "@{set}"))
    }
}

/// The error of a run at one moment.
#[derive(Debug, Clone, Copy)]
pub struct ErrorSample {
    /// Seconds on the run's clock: rendering (and the set-up when it is on the clock),
    /// without the error evaluations.
    pub seconds: f64,
    /// Frames rendered.
    pub frames: u32,
    /// Samples per pixel.
    pub samples_per_pixel: u64,
    /// Error against the reference.
    pub error: ImageError,
}

/// One run's curve.
#[derive(Debug, Clone)]
pub struct RunCurve {
    /// `graph:layout`.
    pub label: String,
    /// Seconds spent planning, compiling and instantiating, and, with the set-up off the
    /// clock, rendering the warm-up frame ([`Session::warm_up`]).
    pub setup_seconds: f64,
    /// Error samples in time order; the last is at the end of the budget.
    pub samples: Vec<ErrorSample>,
    /// Camera samples (paths) per second over the run's clock (set-up on it or not, as its
    /// budget says).
    pub samples_per_second: f64,
}

/// One run's curve and final image.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Its curve.
    pub curve: RunCurve,
    /// The final image.
    pub image: Image,
}

impl RunCurve {
    /// The last error sample.
    pub fn last(&self) -> &ErrorSample {
        self.samples.last().expect("a run has at least one error sample")
    }
}

/// Fewest error samples a run takes after its first frame.
pub const MIN_SAMPLES: usize = 12;

/// The times (seconds) at which errors are sampled after the first frame ended at `first`:
/// log-spaced from there to `budget`, `per_decade` per decade and at least [`MIN_SAMPLES`].
pub fn sample_times(first: f64, budget: f64, per_decade: u32) -> Vec<f64> {
    if first >= budget {
        return Vec::new();
    }
    let ratio = budget / first;
    let n = ((per_decade as f64 * ratio.log10()).ceil() as usize).max(MIN_SAMPLES);
    (1..=n).map(|k| first * ratio.powf(k as f64 / n as f64)).collect()
}

/// A run's wall-clock budget, and whether its set-up (pipeline creation, the session's
/// buffers, the first frame's shader compilation) counts on it: by default not (on a fresh
/// GPU a large graph's pipelines take seconds to create, a budget of a few seconds then
/// measures the driver, not the estimator).
#[derive(Debug, Clone, Copy)]
pub struct RunBudget {
    /// Seconds of rendering (and set-up, with `setup_on_clock`).
    pub time: Duration,
    /// Whether the clock starts before the session's set-up (then no warm-up frame: the
    /// first frame's compilation, where a driver does it then, is on the clock as well).
    pub setup_on_clock: bool,
}

impl RunBudget {
    /// The budget as reports state it.
    pub fn describe(&self) -> String {
        let setup = if self.setup_on_clock { "on" } else { "off" };
        format!("{:?} (set-up {setup} the clock, error evaluation off it)", self.time)
    }
}

/// Renders the run `job` (called `label`) for `budget` on its clock and samples
/// its error against `reference` after the first frame, then at log-spaced times (see
/// [`sample_times`]) and after the last frame; `progress` sees the clock, the latest error and
/// the image it was measured on. With the set-up off the clock, a warm-up frame rendered and
/// thrown away ([`Session::warm_up`]) is part of it. A signal ([`crate::interrupt`]) ends the
/// run at its next batch of frames with [`Interrupted`]: a partial run is not comparable.
pub fn run(
    gpu: &Gpu,
    job: &Run,
    label: String,
    budget: RunBudget,
    reference: &[[f32; 3]],
    per_decade: u32,
    mut progress: impl FnMut(f64, Option<&ErrorSample>, &[[f32; 3]]),
) -> Result<RunResult> {
    let started = Instant::now();
    let mut session = job.session(gpu)?;
    if !budget.setup_on_clock {
        session.warm_up()?;
    }
    let setup_seconds = started.elapsed().as_secs_f64();
    let mut clock = Stopwatch::started_at(if budget.setup_on_clock { started } else { Instant::now() });
    let time = budget.time;
    let mut curve = ErrorCurve {
        reference,
        samples: Vec::new(),
        times: Vec::new(),
        budget: time.as_secs_f64(),
        progress: &mut progress,
    };
    session.render_frame()?;
    curve.measure(&mut session, &mut clock)?;
    curve.times = sample_times(clock.seconds(), curve.budget, per_decade);
    curve.times.reverse();
    let plan = Plan::new(Budget::Time(time));
    if let Ended::Signal(signal) = drive(&mut session, plan, &mut clock, &mut [&mut curve])? {
        let what = format!("run {label} dropped at {:.2} s of {} s", clock.seconds(), curve.budget);
        return Err(Interrupted { signal, what }.into());
    }
    if curve.samples.last().is_some_and(|s| s.frames != session.frames) {
        curve.measure(&mut session, &mut clock)?;
    }
    let samples = curve.samples;
    let image = session.image()?;
    let curve = RunCurve {
        samples_per_second: paths_per_second(&samples, image.mean.len()),
        label,
        setup_seconds,
        samples,
    };
    Ok(RunResult { curve, image })
}

/// The error curve of a run: its error against `reference` measured with the clock stopped
/// (the batch in flight waited for on the clock) at the sample times and at the end of the
/// budget.
struct ErrorCurve<'a, P> {
    reference: &'a [[f32; 3]],
    samples: Vec<ErrorSample>,
    /// The sample times still to come, the next one last.
    times: Vec<f64>,
    budget: f64,
    progress: &'a mut P,
}

impl<P: FnMut(f64, Option<&ErrorSample>, &[[f32; 3]])> ErrorCurve<'_, P> {
    /// Samples the error now.
    fn measure(&mut self, session: &mut Session, clock: &mut Stopwatch) -> Result<()> {
        session.settle()?;
        let seconds = clock.seconds();
        clock.pause();
        let image = session.image()?;
        self.samples.push(ErrorSample {
            seconds,
            frames: session.frames,
            samples_per_pixel: session.samples_per_pixel(),
            error: image_error(&image.mean, self.reference),
        });
        // Off the clock too: the progress may send the image to a live view.
        (self.progress)(seconds, self.samples.last(), &image.mean);
        clock.resume();
        Ok(())
    }
}

impl<P: FnMut(f64, Option<&ErrorSample>, &[[f32; 3]])> Observer<Session<'_>> for ErrorCurve<'_, P> {
    fn batch(&mut self, session: &mut Session, clock: &mut Stopwatch) -> Result<()> {
        let now = clock.seconds();
        if self.times.last().is_some_and(|&t| now >= t) || now >= self.budget {
            while self.times.pop_if(|t| *t <= now).is_some() {}
            self.measure(session, clock)?;
        }
        Ok(())
    }

    fn due(&self) -> Option<f64> {
        self.times.last().copied()
    }
}

/// Camera samples (paths) per second over a curve of an image of `pixels` pixels: its last
/// sample's paths over its clock.
pub fn paths_per_second(samples: &[ErrorSample], pixels: usize) -> f64 {
    samples
        .last()
        .map_or(0.0, |s| s.samples_per_pixel as f64 * pixels as f64 / s.seconds)
}

/// A file-name-safe form of a run label.
pub fn file_stem(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

/// What the report says about the comparison besides the runs.
pub struct ReportContext<'a> {
    /// Scene name.
    pub scene: &'a str,
    /// GPU description.
    pub device: &'a str,
    /// Seconds the scene took to load, BVH build included (not on any run's clock).
    pub load_seconds: f64,
    /// Budget of each run.
    pub budget: RunBudget,
    /// The reference file.
    pub reference_path: &'a Path,
    /// The reference.
    pub reference: &'a Film,
    /// Label of the baseline run (when it has not run yet, the first run that has stands in).
    pub baseline: &'a str,
    /// Runs of the comparison, finished or not (the report may hold fewer: those done).
    pub run_count: usize,
}

/// Writes a run's final image as `<label>.exr` and `<label>.png` into `dir`.
pub fn write_run_images(dir: &Path, scene: &str, run: &RunResult, exposure: f32) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (curve, last) = (&run.curve, run.curve.last());
    let stem = dir.join(file_stem(&curve.label));
    let meta = [
        ("run", curve.label.clone()),
        ("scene", scene.to_string()),
        ("seconds", format!("{:.3}", last.seconds)),
        ("samples_per_pixel", last.samples_per_pixel.to_string()),
    ];
    crate::output::write_exr(&stem.with_extension("exr"), &run.image, &meta)?;
    crate::output::write_png(&stem.with_extension("png"), &run.image, exposure)
}

/// Writes `curves.csv`, `rmse_vs_time.png`, `summary.md` and `report.html` of the finished
/// `runs` into `dir` (their images: [`write_run_images`]); returns the summary.
pub fn write_report(dir: &Path, ctx: &ReportContext, runs: &[RunCurve]) -> Result<String> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut csv = String::from(
        "run,seconds,setup_seconds,frames,samples_per_pixel,mse,rmse,rel_mse,non_finite_pixels,reference_floor_mse\n",
    );
    let floor = ctx.reference.noise_floor_mse();
    for r in runs {
        for s in &r.samples {
            writeln!(
                csv,
                "{},{:.6},{:.6},{},{},{:e},{:e},{:e},{},{floor:e}",
                r.label,
                s.seconds,
                r.setup_seconds,
                s.frames,
                s.samples_per_pixel,
                s.error.mse,
                s.error.rmse,
                s.error.rel_mse,
                s.error.non_finite
            )?;
        }
    }
    let csv_path = dir.join("curves.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    let series: Vec<Series> = runs
        .iter()
        .map(|r| Series {
            label: r.label.clone(),
            points: r.samples.iter().map(|s| (s.seconds, s.error.rmse)).collect(),
        })
        .collect();
    let title = format!("RMSE vs time: {} on {}", ctx.scene, ctx.device);
    let setup = if ctx.budget.setup_on_clock {
        "included"
    } else {
        "excluded"
    };
    let x_label = format!("time [s] (set-up {setup}, error evaluation excluded)");
    let axes = Axes {
        title: &title,
        x_label: &x_label,
        y_label: "RMSE (linear radiance)",
        log_x: true,
        log_y: true,
        legend: plotters::prelude::SeriesLabelPosition::UpperRight,
    };
    line_plot(&dir.join("rmse_vs_time.png"), &axes, &series)?;
    let summary = summary(ctx, runs)?;
    let md = dir.join("summary.md");
    std::fs::write(&md, &summary).with_context(|| format!("writing {}", md.display()))?;
    html::write_html(dir, ctx, runs, &summary)?;
    Ok(summary)
}

/// The summary: what was compared, then per run its final errors, slope, noise and time to
/// the baseline's final error.
fn summary(ctx: &ReportContext, runs: &[RunCurve]) -> Result<String> {
    let Some(base) = runs.iter().find(|r| r.label == ctx.baseline).or(runs.first()) else {
        return Ok(format!(
            "# Error against time: {}

No run finished yet.
",
            ctx.scene
        ));
    };
    let target = base.last().error.rmse;
    let floor = ctx.reference.noise_floor_mse().sqrt();
    let info = |k: &str| ctx.reference.info.get(k).cloned().unwrap_or_default();
    let mut s = String::new();
    writeln!(s, "# Error against time: {}\n", ctx.scene)?;
    if runs.len() < ctx.run_count {
        writeln!(s, "**{} of {} runs done so far.**\n", runs.len(), ctx.run_count)?;
    }
    writeln!(s, "- device: {}", ctx.device)?;
    writeln!(s, "- budget: {} per run", ctx.budget.describe())?;
    writeln!(
        s,
        "- scene load and BVH build: {:.2} s (before the runs, on no clock)",
        ctx.load_seconds
    )?;
    writeln!(
        s,
        "- reference: `{}`: graph {} layout {}, {} spp, seed {}; its own noise is RMSE {floor:.3e}",
        ctx.reference_path.display(),
        info("graph"),
        info("layout"),
        ctx.reference.samples_per_pixel(),
        info("seed")
    )?;
    let stand_in = if base.label == ctx.baseline {
        String::new()
    } else {
        format!(" (standing in for the baseline {}, not run yet)", ctx.baseline)
    };
    writeln!(
        s,
        "- target: RMSE {target:.4e}, what the baseline **{}**{stand_in} reaches at the end of its budget\n",
        base.label
    )?;
    let extrapolated = run_table(&mut s, runs, base, target)?;
    legend(&mut s, extrapolated)?;
    if floor > 0.5 * target {
        writeln!(
            s,
            "\n**Warning**: the reference's own noise (RMSE {floor:.3e}) is more than half the target; \
             render a longer reference (`lightgraph reference --resume`) before trusting these numbers."
        )?;
    }
    let bad: Vec<&str> = runs
        .iter()
        .filter(|r| r.last().error.non_finite > 0)
        .map(|r| r.label.as_str())
        .collect();
    if !bad.is_empty() {
        writeln!(s, "\n**Warning**: NaN or infinite pixels in {}.", bad.join(", "))?;
    }
    Ok(s)
}

/// The table of runs; returns whether a time to the target was extrapolated.
fn run_table(s: &mut String, runs: &[RunCurve], base: &RunCurve, target: f64) -> Result<bool> {
    let (base_time, _) = time_to_error(&base.samples, target).unwrap_or((f64::NAN, false));
    writeln!(
        s,
        "| run | set-up s | frames | spp | Msamples/s | final RMSE | noise | final relMSE | slope | time to target s | speed-up |"
    )?;
    writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut extrapolated = false;
    for r in runs {
        let last = r.last();
        let slope = convergence_slope(&r.samples).map_or("n/a".to_string(), |v| format!("{v:.2}"));
        let noise = tail_noise(&r.samples).map_or("n/a".to_string(), |v| format!("{:.1}%", 100.0 * v));
        let (time, speedup) = match time_to_error(&r.samples, target) {
            Some((t, x)) => {
                extrapolated |= x;
                let mark = if x { " ‡" } else { "" };
                (format!("{t:.3}{mark}"), format!("{:.2}×", base_time / t))
            }
            None => ("never".to_string(), "n/a".to_string()),
        };
        writeln!(
            s,
            "| {} | {:.2} | {} | {} | {:.2} | {:.4e} | {noise} | {:.4e} | {slope} | {time} | {speedup} |",
            r.label,
            r.setup_seconds,
            last.frames,
            last.samples_per_pixel,
            r.samples_per_second / 1e6,
            last.error.rmse,
            last.error.rel_mse
        )?;
    }
    Ok(extrapolated)
}

/// What the table's columns mean.
fn legend(s: &mut String, extrapolated: bool) -> Result<()> {
    writeln!(
        s,
        "\nTime to target: when the run's curve reached the target **and stayed at or below it** to \
         the end (interpolated log-log between its last sample above and the next; a dip below \
         that comes back up does not count). Speed-up = the baseline's time to the target over \
         the run's. Set-up: pipeline creation and instantiation, and with the set-up off the clock \
         a warm-up frame rendered and thrown away (so the first frame's shader compilation, which \
         some drivers do at the first dispatch, is not on the clock either). Noise: the relative \
         scatter of the run's log RMSE from sample to sample over the last 1.5 decades (the median \
         of its second differences), how uncertain its final RMSE is. Slope: least-squares slope \
         of log RMSE against log time since the run's first error sample, over the last 1.5 decades \
         (−0.5 is the Monte Carlo rate; flatter means bias, or that the error nears the reference's \
         own noise; a few very noisy pixels, such as the edges of a visible light, make it wander)."
    )?;
    if extrapolated {
        writeln!(
            s,
            "\n‡ The run ended above the target: its time is extrapolated from its last sample at the \
             Monte Carlo rate (time ∝ RMSE⁻²)."
        )?;
    }
    Ok(())
}

/// The estimators a list of `graph[:Layout][@NAME=VALUE...]` names (option `flag`), each
/// graph, named layout and constant checked, none named twice.
pub fn estimator_specs(list: &str, flag: &str) -> Result<Vec<EstimatorSpec>> {
    if list.split(',').all(|s| s.trim().is_empty()) {
        bail!("{flag} names no estimator; give graphs or graph:Layout pairs, e.g. pt,bpt-lvc:LVC-BPTmk");
    }
    let specs = EstimatorSpec::parse_list(list)?;
    for (i, spec) in specs.iter().enumerate() {
        if specs[..i].contains(spec) {
            bail!("{flag} names {spec} twice");
        }
        let graph = load_graph(&spec.graph).with_context(|| format!("{flag} {spec}"))?;
        if let Some(layout) = &spec.layout {
            named_layout(&graph, Some(layout)).with_context(|| format!("{flag} {spec}"))?;
        }
        parse_sets(&spec.sets, &graph, &format!("{flag} @"))?;
    }
    Ok(specs)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A curve of error samples at `(seconds, RMSE)` points.
    pub(crate) fn curve(points: &[(f64, f64)]) -> Vec<ErrorSample> {
        points
            .iter()
            .map(|&(t, e)| ErrorSample {
                seconds: t,
                frames: 1,
                samples_per_pixel: 1,
                error: ImageError {
                    mse: e * e,
                    rmse: e,
                    rel_mse: e,
                    non_finite: 0,
                },
            })
            .collect()
    }

    #[test]
    fn run_lists_parse() {
        let runs = EstimatorSpec::parse_list("pt:NaivePTsk, pt ,tests/x.ron:L").unwrap();
        assert_eq!(runs[0].layout.as_deref(), Some("NaivePTsk"));
        assert_eq!((runs[1].graph.as_str(), runs[1].layout.as_ref()), ("pt", None));
        assert_eq!(
            (runs[2].graph.as_str(), runs[2].layout.as_deref()),
            ("tests/x.ron", Some("L"))
        );
        assert!(EstimatorSpec::parse_list(" , ").is_err());
        let set = EstimatorSpec::parse_list("ppm:PPMsk@PM_STRUCTURE=3@PM_ALPHA=1, ppm@PM_STRUCTURE=1").unwrap();
        assert_eq!(set[0].layout.as_deref(), Some("PPMsk"));
        assert_eq!(set[0].sets, ["PM_STRUCTURE=3", "PM_ALPHA=1"]);
        assert_eq!((set[1].graph.as_str(), set[1].layout.as_ref()), ("ppm", None));
        assert_eq!(set[1].sets, ["PM_STRUCTURE=1"]);
        let text: Vec<String> = set.iter().map(EstimatorSpec::to_string).collect();
        assert_eq!(text, ["ppm:PPMsk@PM_STRUCTURE=3@PM_ALPHA=1", "ppm@PM_STRUCTURE=1"]);
    }

    #[test]
    fn sample_times_are_log_spaced_from_the_first_frame_to_the_budget() {
        let t = sample_times(0.01, 10.0, 6);
        assert_eq!(t.len(), 18);
        assert!((t[17] - 10.0).abs() < 1e-12);
        for w in t.windows(2) {
            assert!((w[1] / w[0] - 10f64.powf(0.5 / 3.0)).abs() < 1e-9);
        }
        // A slow first frame still leaves a curve.
        assert_eq!(sample_times(8.0, 10.0, 6).len(), MIN_SAMPLES);
        assert!(sample_times(10.0, 10.0, 6).is_empty());
    }

    #[test]
    fn a_paused_stopwatch_stands_still() {
        let mut w = Stopwatch::started_at(Instant::now());
        w.pause();
        let t = w.seconds();
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(w.seconds(), t);
        w.resume();
        std::thread::sleep(Duration::from_millis(5));
        assert!(w.seconds() > t);
    }
}
