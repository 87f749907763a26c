//! A study's HTML report: the summary, and per scene the error against time of every
//! estimator (with each curve's uncertainty) and the reference and final images in a viewer.

use super::summary::SceneRuns;
use crate::compare::ErrorSample;
use crate::compare::html::{add_images, error_plot};
use crate::film::Film;
use crate::report::Report;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// Where a study writes its HTML report in its folder `dir`.
pub fn html_path(dir: &Path) -> PathBuf {
    dir.join("report.html")
}

/// Writes the study's HTML report ([`html_path`]): the summary `md`, then per scene done its
/// plot and its images (read from the scene's comparison folder and reference).
pub fn write_html(dir: &Path, md: &str, scenes: &[SceneRuns]) -> Result<()> {
    let mut report = Report::new("Study");
    report.markdown(md);
    for scene in scenes {
        let reference = Film::read(Path::new(&scene.reference.path))?;
        let curves: Vec<(&str, &[ErrorSample])> = scene
            .runs
            .iter()
            .map(|r| (r.estimator.as_str(), r.samples.as_slice()))
            .collect();
        let title = format!("RMSE against time: {}", scene.scene);
        report.plot(error_plot(
            &title,
            "time [s] (error evaluation excluded)",
            &curves,
            scene.reference.noise_rmse,
        ));
        let labels: Vec<&str> = scene.runs.iter().map(|r| r.label.as_str()).collect();
        let images = (reference.size, reference.mean());
        add_images(
            &mut report,
            &scene.scene,
            (images.0, &images.1),
            &dir.join(&scene.folder),
            &labels,
        )?;
    }
    report.write(&html_path(dir))
}
