//! The HTML report of `render --reference`: the render's error against the reference over
//! time, and the render and the reference in a viewer ([`lightgraph::report`]).

use anyhow::Result;
use lightgraph::compare::ErrorSample;
use lightgraph::compare::html::error_plot;
use lightgraph::film::Film;
use lightgraph::report::Report;
use std::path::{Path, PathBuf};

/// Where `render --reference --out X.exr` writes its HTML report: `X.html`.
pub fn html_path(out: &Path) -> PathBuf {
    lightgraph::report::beside(out)
}

/// Writes the report ([`html_path`]) of the film written to `out`, rendered with `layout`
/// against the reference at `path`, whose error was `errors` over this run's time.
pub fn write_html(out: &Path, film: &Film, (path, layout): (&Path, &str), errors: &[ErrorSample]) -> Result<()> {
    let reference = Film::read(path)?;
    let floor = reference.noise_floor_mse().sqrt();
    let info = |k: &str| film.info.get(k).cloned().unwrap_or_default();
    let (w, h) = film.size;
    let last = errors.last().map(|e| e.error);
    let md = format!(
        "# Render: {}\n\n- graph {} layout {layout}, {w}x{h}, {} spp in {:.2} s\n\
         - reference `{}`: {} spp; its own noise: RMSE {floor:.4e}\n\
         - final error: RMSE {:.4e}, relMSE {:.4e}\n",
        info("scene"),
        info("graph"),
        film.samples_per_pixel(),
        film.seconds,
        path.display(),
        reference.samples_per_pixel(),
        last.map_or(f64::NAN, |e| e.rmse),
        last.map_or(f64::NAN, |e| e.rel_mse),
    );
    let mut report = Report::new(&format!("Render: {}", info("scene")));
    report.markdown(&md);
    let curve = [(info("graph"), errors)];
    let curves: Vec<(&str, &[ErrorSample])> = curve.iter().map(|(l, e)| (l.as_str(), *e)).collect();
    report.plot(error_plot("RMSE against time", "time [s] of this run", &curves, floor));
    report.viewer(&info("scene"));
    let name = out
        .file_name()
        .map_or("render".into(), |n| n.to_string_lossy().to_string());
    report.image(&name, w, h, &film.mean());
    report.image("reference", w, h, &reference.mean());
    report.write(&html_path(out))
}
