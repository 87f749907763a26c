//! PNG line plots for reports (rays/s against paths per frame, error against time), drawn
//! with plotters and an embedded font, so they render anywhere the binary runs.

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// A short tick label: 3e5 as "300k", 2.5e7 as "25M", 0.04000001 as "0.04", 2.5e-4 as
/// "2.5e-4": three significant digits at most, no float noise.
fn compact(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a < 1e-2 {
        let s = format!("{v:.1e}");
        return s.replacen(".0e", "e", 1);
    }
    let (x, suffix) = if a >= 1e9 {
        (v / 1e9, "G")
    } else if a >= 1e6 {
        (v / 1e6, "M")
    } else if a >= 1e3 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    let digits = (2 - x.abs().max(1e-300).log10().floor() as i32).clamp(0, 4) as usize;
    let s = format!("{x:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    format!("{s}{suffix}")
}

/// A logarithmic axis over `lo..hi` with ticks at 1, 2 and 5 times the powers of ten (only
/// at the powers when the range spans more than four decades).
fn log_axis(
    lo: f64,
    hi: f64,
) -> plotters::coord::combinators::WithKeyPoints<plotters::coord::combinators::LogCoord<f64>> {
    let steps: &[f64] = if hi / lo > 1e4 { &[1.0] } else { &[1.0, 2.0, 5.0] };
    let ticks = (lo.log10().floor() as i32..=hi.log10().ceil() as i32)
        .flat_map(|e| steps.iter().map(move |m| m * 10f64.powi(e)))
        .filter(|v| (lo..=hi).contains(v))
        .collect();
    (lo..hi).log_scale().with_key_points(ticks)
}

/// One named series of (x, y) points.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points, in x order.
    pub points: Vec<(f64, f64)>,
}

/// Axes of a line plot.
pub struct Axes<'a> {
    /// Plot title.
    pub title: &'a str,
    /// X axis label.
    pub x_label: &'a str,
    /// Y axis label.
    pub y_label: &'a str,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Corner of the legend: one the curves leave free.
    pub legend: SeriesLabelPosition,
}

/// Draws `series` as lines with markers into a 1200x750 PNG at `path`.
pub fn line_plot(path: &Path, axes: &Axes, series: &[Series]) -> Result<()> {
    register_font();
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if all.is_empty() {
        return Err(anyhow!("nothing to plot in {}", path.display()));
    }
    let range = |v: Vec<f64>, log: bool| {
        let v: Vec<f64> = v.into_iter().filter(|x| !log || *x > 0.0).collect();
        let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        if log {
            (lo / 1.5, hi * 1.5)
        } else {
            (lo.min(0.0), hi * 1.1 + 1e-12)
        }
    };
    let (x0, x1) = range(all.iter().map(|p| p.0).collect(), axes.log_x);
    let (y0, y1) = range(all.iter().map(|p| p.1).collect(), axes.log_y);
    let root = BitMapBackend::new(path, (1200, 750)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(axes.title, ("sans-serif", 28))
        .margin(20)
        .x_label_area_size(60)
        .y_label_area_size(90);
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart.map_err(|e| anyhow!("{e}"))?;
            chart
                .configure_mesh()
                .x_desc(axes.x_label)
                .x_label_formatter(&|v| compact(*v))
                .y_label_formatter(&|v| compact(*v))
                .y_desc(axes.y_label)
                .label_style(("sans-serif", 18))
                .axis_desc_style(("sans-serif", 22))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
            for (i, s) in series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|(x, y)| (!axes.log_x || *x > 0.0) && (!axes.log_y || *y > 0.0))
                    .collect();
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(|e| anyhow!("{e}"))?
                    .label(s.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 16))
                .position(axes.legend.clone())
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
        }};
    }
    match (axes.log_x, axes.log_y) {
        (true, true) => draw!(builder.build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))),
        (true, false) => draw!(builder.build_cartesian_2d(log_axis(x0, x1), y0..y1)),
        (false, true) => draw!(builder.build_cartesian_2d(x0..x1, log_axis(y0, y1))),
        (false, false) => draw!(builder.build_cartesian_2d(x0..x1, y0..y1)),
    }
    root.present().map_err(|e| anyhow!("writing {}: {e}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::compact;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(compact(3e5), "300k");
        assert_eq!(compact(2.5e7), "25M");
        assert_eq!(compact(0.04000000001), "0.04");
        assert_eq!(compact(0.6000000000001), "0.6");
        assert_eq!(compact(1.0), "1");
        assert_eq!(compact(12.5), "12.5");
        assert_eq!(compact(2.5e-4), "2.5e-4");
        assert_eq!(compact(1e-3), "1e-3");
    }
}
