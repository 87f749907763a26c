//! Measuring layouts: one measurement is a layout rendering frames of a given size for a time
//! budget; `bench` sweeps paths per frame (the paper's Table I and Figure 3) and writes a
//! Markdown table, a CSV and a PNG plot.

use crate::drive::{Budget, Plan, Stopwatch, drive};
use crate::plot::{Axes, Series, line_plot};
use crate::run::{Run, Session};
use anyhow::{Context, Result};
use lightgraph_engine::Gpu;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;
use std::time::Duration;

/// One layout measured at one frame size.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// Layout name.
    pub layout: String,
    /// Image width and height.
    pub resolution: (u32, u32),
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Frames rendered in the timed part (after one warm-up frame).
    pub frames: u32,
    /// Wall-clock seconds of the timed part.
    pub seconds: f64,
    /// Rays traced in the timed part (primary, extension, shadow: every `rays_*` counter).
    pub rays: u64,
    /// Sum of the kernels' GPU time in the timed part.
    pub gpu_seconds: f64,
    /// GPU milliseconds per frame of each kernel.
    pub kernel_ms: BTreeMap<String, f64>,
    /// GPU memory the layout allocates, scene data included.
    pub memory_bytes: u64,
}

impl Measurement {
    /// Paths (camera samples) per frame.
    pub fn paths_per_frame(&self) -> u64 {
        self.resolution.0 as u64 * self.resolution.1 as u64 * self.spp as u64
    }
    /// Camera samples per second, wall-clock.
    pub fn samples_per_second(&self) -> f64 {
        self.paths_per_frame() as f64 * self.frames as f64 / self.seconds
    }
    /// Rays per second, wall-clock.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds
    }
    /// Rays per second of GPU kernel time.
    pub fn gpu_rays_per_second(&self) -> f64 {
        self.rays as f64 / self.gpu_seconds.max(1e-12)
    }
    /// Frames per second.
    pub fn frames_per_second(&self) -> f64 {
        self.frames as f64 / self.seconds
    }
}

/// Compiles `run` on `gpu` ([`Run::session`]), then [`measure_session`].
pub fn measure(gpu: &Gpu, run: &Run, budget: Duration) -> Result<Measurement> {
    measure_session(&mut run.session(gpu)?, &run.layout, budget)
}

/// Renders one warm-up frame of `session` (of the layout called `layout`), then frames until
/// `budget` has passed (at least one).
pub fn measure_session(session: &mut Session, layout: &str, budget: Duration) -> Result<Measurement> {
    let options = &session.options;
    let (resolution, spp) = ((options.width, options.height), options.samples_per_frame);
    session.render_frame()?;
    let (rays0, kernels0) = (session.rays(), session.kernel_seconds.clone());
    let mut clock = Stopwatch::start();
    let frames0 = session.frames;
    drive(
        session,
        Plan::new(Budget::Time(budget)).at_least(1),
        &mut clock,
        &mut [],
    )?
    .whole("the measurement")?;
    let seconds = clock.seconds();
    let frames = session.frames - frames0;
    let kernel_ms: BTreeMap<String, f64> = session
        .kernel_seconds
        .iter()
        .map(|(k, v)| {
            (
                k.clone(),
                1e3 * (v - kernels0.get(k).copied().unwrap_or(0.0)) / frames as f64,
            )
        })
        .collect();
    Ok(Measurement {
        layout: layout.to_string(),
        resolution,
        spp,
        frames,
        seconds,
        rays: session.rays() - rays0,
        gpu_seconds: kernel_ms.values().sum::<f64>() * frames as f64 / 1e3,
        kernel_ms,
        memory_bytes: session.memory_bytes(),
    })
}

/// The paper's range of paths per frame (3.3e5 to 1e8) as (width, height, spp).
pub const DEFAULT_POINTS: [(u32, u32, u32); 7] = [
    (768, 432, 1),
    (1280, 720, 1),
    (1280, 720, 2),
    (1280, 720, 4),
    (1280, 720, 11),
    (1280, 720, 33),
    (1280, 720, 108),
];

fn mega(v: f64) -> String {
    format!("{:.1}", v / 1e6)
}

/// A count with a k / M suffix.
fn count(v: u64) -> String {
    if v >= 1_000_000 {
        format!("{:.2} M", v as f64 / 1e6)
    } else {
        format!("{:.1} k", v as f64 / 1e3)
    }
}

/// Writes `bench.csv`, `bench.md` (Mrays/s per layout and frame size, the paper's Table I
/// form, plus a detail table), `rays_per_second.png` and `report.html` ([`html_path`]) into
/// `dir`; returns the Markdown.
pub fn write_reports(dir: &Path, title: &str, results: &[Measurement]) -> Result<String> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    std::fs::write(dir.join("bench.csv"), bench_csv(results))?;
    let md = bench_markdown(title, results);
    std::fs::write(dir.join("bench.md"), &md)?;
    let plot = rates_plot(title, results);
    plot_rates(&dir.join("rays_per_second.png"), &plot)?;
    let mut report = crate::report::Report::new("lightgraph bench");
    report.markdown(&md).plot(plot);
    report.write(&html_path(dir))?;
    Ok(md)
}

/// Where `bench` writes its HTML report in its output folder `dir`.
pub fn html_path(dir: &Path) -> std::path::PathBuf {
    dir.join("report.html")
}

/// The HTML report's plot of rays/s against paths per frame, a line per layout.
fn rates_plot(title: &str, results: &[Measurement]) -> crate::report::Plot {
    let (layouts, _) = layouts_and_sizes(results);
    let line = |l: &str| crate::report::Line {
        label: l.to_string(),
        points: results
            .iter()
            .filter(|m| m.layout == l)
            .map(|m| (m.paths_per_frame() as f64, m.rays_per_second() / 1e9, None, None))
            .collect(),
        dashed: false,
    };
    crate::report::Plot {
        title: title.to_string(),
        x_label: "paths per frame".to_string(),
        y_label: "rays per second (10^9, wall-clock)".to_string(),
        log_x: true,
        log_y: false,
        lines: layouts.iter().map(|l| line(l)).collect(),
        note: "One measurement per point (no band): repeat the run to see its spread.".to_string(),
    }
}

/// The layouts and the paths per frame measured, each once: layouts in the order measured,
/// sizes ascending.
fn layouts_and_sizes(results: &[Measurement]) -> (Vec<&str>, Vec<u64>) {
    let mut layouts: Vec<&str> = Vec::new();
    let mut sizes: Vec<u64> = Vec::new();
    for m in results {
        if !layouts.contains(&m.layout.as_str()) {
            layouts.push(&m.layout);
        }
        if !sizes.contains(&m.paths_per_frame()) {
            sizes.push(m.paths_per_frame());
        }
    }
    sizes.sort();
    (layouts, sizes)
}

/// One CSV row per measurement.
fn bench_csv(results: &[Measurement]) -> String {
    let mut csv = String::from(
        "layout,width,height,spp,paths_per_frame,frames,seconds,rays,rays_per_s,gpu_rays_per_s,samples_per_s,frames_per_s,memory_mib,kernel_ms\n",
    );
    for m in results {
        let kernels: Vec<String> = m.kernel_ms.iter().map(|(k, v)| format!("{k}={v:.4}")).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{:.4},{},{:.0},{:.0},{:.0},{:.2},{:.1},{}",
            m.layout,
            m.resolution.0,
            m.resolution.1,
            m.spp,
            m.paths_per_frame(),
            m.frames,
            m.seconds,
            m.rays,
            m.rays_per_second(),
            m.gpu_rays_per_second(),
            m.samples_per_second(),
            m.frames_per_second(),
            m.memory_bytes as f64 / 1048576.0,
            kernels.join(";")
        );
    }
    csv
}

/// The Markdown report: Mrays/s by layout and paths per frame, then a row of detail per
/// measurement.
fn bench_markdown(title: &str, results: &[Measurement]) -> String {
    let (layouts, sizes) = layouts_and_sizes(results);
    let mut md = format!(
        "## {title}\n\nMillions of rays per second (wall-clock; GPU-time rate in parentheses), by paths per frame.\n\n| layout |"
    );
    for s in &sizes {
        let _ = write!(md, " {} |", count(*s));
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(sizes.len()));
    md.push('\n');
    for l in &layouts {
        let _ = write!(md, "| {l} |");
        for s in &sizes {
            match results.iter().find(|m| m.layout == *l && m.paths_per_frame() == *s) {
                Some(m) => {
                    let _ = write!(
                        md,
                        " {} ({}) |",
                        mega(m.rays_per_second()),
                        mega(m.gpu_rays_per_second())
                    );
                }
                None => md.push_str(" – |"),
            }
        }
        md.push('\n');
    }
    md.push_str("\n| layout | paths/frame | frames/s | Msamples/s | memory MiB | GPU ms per frame by kernel |\n|---|---|---|---|---|---|\n");
    for m in results {
        let kernels: Vec<String> = m.kernel_ms.iter().map(|(k, v)| format!("{k} {v:.3}")).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {} | {:.1} | {} |",
            m.layout,
            count(m.paths_per_frame()),
            m.frames_per_second(),
            mega(m.samples_per_second()),
            m.memory_bytes as f64 / 1048576.0,
            kernels.join(", ")
        );
    }
    md
}

/// Draws the plot of rays/s against paths per frame ([`rates_plot`]) as a PNG into `path`.
fn plot_rates(path: &Path, plot: &crate::report::Plot) -> Result<()> {
    let series: Vec<Series> = plot
        .lines
        .iter()
        .map(|l| Series {
            label: l.label.clone(),
            points: l.points.iter().map(|p| (p.0, p.1)).collect(),
        })
        .collect();
    line_plot(
        path,
        &Axes {
            title: &plot.title,
            x_label: &plot.x_label,
            y_label: &plot.y_label,
            log_x: plot.log_x,
            log_y: plot.log_y,
            legend: plotters::prelude::SeriesLabelPosition::LowerRight,
        },
        &series,
    )
}
