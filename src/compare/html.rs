//! The HTML reports of comparisons (`compare`, and each scene of a `study`): the summary,
//! error against time with each curve's uncertainty, and the reference and every run's
//! final image in a viewer ([`crate::report`]).

use super::{ErrorSample, ReportContext, RunCurve, file_stem, tail_noise};
use crate::report::{Line, Plot, Report};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// Where a comparison writes its HTML report in its folder `dir`.
pub fn html_path(dir: &Path) -> PathBuf {
    dir.join("report.html")
}

/// What the bands of [`error_plot`] are.
const BANDS: &str = "Bands: each curve's RMSE times e^(±σ), σ its relative sample-to-sample scatter over its last \
                     1.5 decades (the summary's noise column); dashed: the reference's own noise (RMSE).";

/// The plot of RMSE against time of `curves` (label, samples), each with a band of its
/// scatter ([`tail_noise`]), and the reference's own noise `floor` (an RMSE) dashed.
pub fn error_plot(title: &str, x_label: &str, curves: &[(&str, &[ErrorSample])], floor: f64) -> Plot {
    let mut lines: Vec<Line> = curves
        .iter()
        .map(|(label, samples)| error_line(label, samples))
        .collect();
    let times = curves.iter().flat_map(|(_, s)| s.iter().map(|s| s.seconds));
    let (first, last) = times.fold((f64::MAX, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
    if floor > 0.0 && first < last {
        lines.push(Line {
            label: "reference noise".to_string(),
            points: vec![(first, floor, None, None), (last, floor, None, None)],
            dashed: true,
        });
    }
    Plot {
        title: title.to_string(),
        x_label: x_label.to_string(),
        y_label: "RMSE".to_string(),
        log_x: true,
        log_y: true,
        lines,
        note: BANDS.to_string(),
    }
}

/// One curve's line, its band from its tail noise (none when it has too few samples).
fn error_line(label: &str, samples: &[ErrorSample]) -> Line {
    let sigma = tail_noise(samples);
    let points = samples
        .iter()
        .map(|s| {
            let e = s.error.rmse;
            (s.seconds, e, sigma.map(|x| e * (-x).exp()), sigma.map(|x| e * x.exp()))
        })
        .collect();
    Line {
        label: label.to_string(),
        points,
        dashed: false,
    }
}

/// Adds a viewer called `title` of the reference (`reference`: size and mean) and of each
/// run's final image, read from `<label>.exr` in `dir`.
pub fn add_images(
    report: &mut Report,
    title: &str,
    (size, reference): ((u32, u32), &[[f32; 3]]),
    dir: &Path,
    labels: &[&str],
) -> Result<()> {
    report.viewer(title).image("reference", size.0, size.1, reference);
    for label in labels {
        let (w, h, rgb) = crate::output::read_rgb(&dir.join(file_stem(label)).with_extension("exr"))?;
        report.image(label, w, h, &rgb);
    }
    Ok(())
}

/// Writes the comparison's HTML report ([`html_path`]): the summary `md`, the error plot and
/// the images of the finished `runs`.
pub fn write_html(dir: &Path, ctx: &ReportContext, runs: &[RunCurve], md: &str) -> Result<()> {
    let mut report = Report::new(&format!("Error against time: {}", ctx.scene));
    report.markdown(md);
    let curves: Vec<(&str, &[ErrorSample])> = runs.iter().map(|r| (r.label.as_str(), r.samples.as_slice())).collect();
    let title = format!("RMSE against time: {} on {}", ctx.scene, ctx.device);
    let floor = ctx.reference.noise_floor_mse().sqrt();
    report.plot(error_plot(
        &title,
        "time [s] (error evaluation excluded)",
        &curves,
        floor,
    ));
    let labels: Vec<&str> = runs.iter().map(|r| r.label.as_str()).collect();
    let reference = (ctx.reference.size, ctx.reference.mean());
    add_images(&mut report, ctx.scene, (reference.0, &reference.1), dir, &labels)?;
    report.write(&html_path(dir))
}
