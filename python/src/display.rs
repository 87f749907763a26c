//! Images shown in Jupyter: a film as PNG (sRGB, 8 bits, at an exposure in stops, as the
//! CLI's previews), and as HTML: the reports' viewer (src/report) for notebooks that run a
//! page's script.

use crate::err;
use ::lightgraph::output::png_bytes;
use ::lightgraph::report::Report;
use ::lightgraph::run::Image;
use numpy::{PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// The PNG file of `image` at `exposure` stops.
pub fn png<'py>(py: Python<'py>, image: &Image, exposure: f32) -> PyResult<Bound<'py, PyBytes>> {
    let bytes = png_bytes(image, exposure).map_err(err)?;
    Ok(PyBytes::new(py, &bytes))
}

/// The report viewer of `image` (src/report: float data tone-mapped in the page, with an
/// exposure slider, zoom and the values under the cursor) under `caption`, in an iframe of
/// its own so that the page's style and script stay out of the notebook's.
pub fn html(py: Python<'_>, image: &Image, label: &str, caption: &str) -> PyResult<String> {
    let mut report = Report::new(label);
    report
        .viewer(caption)
        .image(label, image.width, image.height, &image.mean);
    let page = report.to_html();
    let escaped: String = py.import("html")?.call_method1("escape", (page, true))?.extract()?;
    // The viewer shows a small image enlarged to about 512 pixels wide; its title and
    // controls take about 250 pixels more.
    let shown = image.height as u64 * 512 / image.width.clamp(1, 512) as u64;
    let height = shown.min(1200) + 250;
    Ok(format!(
        "<iframe srcdoc=\"{escaped}\" style=\"width:100%;height:{height}px;border:0;resize:vertical\"></iframe>"
    ))
}

/// The PNG file (bytes) of an image (a float32 array of shape (height, width, 3), as
/// `render`, `Session.image` and `read` return them) at `exposure` stops, sRGB in 8 bits as
/// the CLI's previews; show it in Jupyter with `IPython.display.Image(lightgraph.to_png(image))`.
///
/// - image: float32 linear radiance of shape (height, width, 3).
/// - exposure: stops to scale the radiance by (2 ** exposure) before the sRGB curve.
#[pyfunction]
#[pyo3(signature = (image, exposure = 0.0))]
pub fn to_png<'py>(py: Python<'py>, image: PyReadonlyArray3<'py, f32>, exposure: f32) -> PyResult<Bound<'py, PyBytes>> {
    let shape = image.shape();
    if shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "image of shape {shape:?}: it must be (height, width, 3)"
        )));
    }
    let values = image.as_array();
    let mean: Vec<[f32; 3]> = values
        .outer_iter()
        .flat_map(|row| row.outer_iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>())
        .collect();
    let image = Image {
        width: shape[1] as u32,
        height: shape[0] as u32,
        frames: 0,
        mean,
        variance: Vec::new(),
    };
    png(py, &image, exposure)
}
