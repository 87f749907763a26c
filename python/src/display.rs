//! Images shown in Jupyter: a film as PNG (sRGB, 8 bits, at an exposure in stops, as the
//! CLI's previews), and as HTML for notebooks that render HTML.

use crate::err;
use ::lightgraph::output::png_bytes;
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

/// An HTML `<img>` of `image` at `exposure` stops (the PNG inline as a data URI), captioned
/// `caption`.
pub fn html(py: Python<'_>, image: &Image, exposure: f32, caption: &str) -> PyResult<String> {
    let png = png(py, image, exposure)?;
    let base64 = py.import("base64")?.call_method1("b64encode", (png,))?;
    let text: String = base64.call_method1("decode", ("ascii",))?.extract()?;
    Ok(format!(
        "<figure style=\"margin:0\"><img style=\"image-rendering:pixelated\" width=\"{}\" height=\"{}\" \
         src=\"data:image/png;base64,{text}\"><figcaption>{caption}</figcaption></figure>",
        image.width.max(256),
        image.height * image.width.max(256) / image.width.max(1),
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
