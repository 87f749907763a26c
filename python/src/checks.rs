//! The keyword arguments checked before any work, with messages that name the keyword
//! (`frames=-1: ...`), as `ValueError`s: counts and times above zero, seeds in range, images
//! that fit, and constants the graph has, of their type.

use ::lightgraph::run::{BvhChoice, checks};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

/// `name=value` as a count of at least 1 that fits a u32.
pub fn count(name: &str, value: i64) -> PyResult<u32> {
    checks::count(&value.to_string()).map_err(|e| PyValueError::new_err(format!("{name}={value}: {e}")))
}

/// An optional count ([`count`] when given).
pub fn count_opt(name: &str, value: Option<i64>) -> PyResult<Option<u32>> {
    value.map(|v| count(name, v)).transpose()
}

/// `name=value` as a seed: a whole number from 0 to 4294967295.
pub fn seed(name: &str, value: i64) -> PyResult<u32> {
    u32::try_from(value)
        .map_err(|_| PyValueError::new_err(format!("{name}={value}: it must be from 0 to {}", u32::MAX)))
}

/// An optional seed ([`seed`] when given).
pub fn seed_opt(name: &str, value: Option<i64>) -> PyResult<Option<u32>> {
    value.map(|v| seed(name, v)).transpose()
}

/// `name=value` seconds: finite and above zero.
pub fn seconds(name: &str, value: f64) -> PyResult<f64> {
    // As Python writes floats: -1.0, nan, inf.
    let shown = match value.is_nan() {
        true => "nan".to_string(),
        false => format!("{value:?}"),
    };
    match value.is_finite() && value > 0.0 {
        true => Ok(value),
        false => Err(PyValueError::new_err(format!(
            "{name}={shown}: it must be a number of seconds above zero"
        ))),
    }
}

/// Optional seconds ([`seconds`] when given).
pub fn seconds_opt(name: &str, value: Option<f64>) -> PyResult<Option<f64>> {
    value.map(|v| seconds(name, v)).transpose()
}

/// `res=(width, height)`: both at least 1, and with `spp` samples per pixel an image whose
/// frame the engine counts and whose film the host holds.
pub fn image(res: Option<(i64, i64)>, spp: u32) -> PyResult<Option<(u32, u32)>> {
    let Some((w, h)) = res else { return Ok(None) };
    let side = |v: i64| checks::count::<u32>(&v.to_string());
    let (width, height) = match (side(w), side(h)) {
        (Ok(width), Ok(height)) => (width, height),
        (Err(e), _) | (_, Err(e)) => {
            return Err(PyValueError::new_err(format!("res=({w}, {h}): width and height: {e}")));
        }
    };
    checks::image_fits(width, height, spp)
        .map_err(|e| PyValueError::new_err(format!("res=({w}, {h}) with spp={spp}: {e}")))?;
    Ok(Some((width, height)))
}

/// Each entry of `constants` checked against graph `graph` (a name or a file): a constant it
/// has, with a value of its type.
pub fn constants(py: Python<'_>, graph: &str, constants: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    let Some(dict) = constants.filter(|d| !d.is_empty()) else {
        return Ok(());
    };
    let loaded = py.detach(|| ::lightgraph::run::load_graph(graph)).map_err(crate::err)?;
    for (k, v) in dict.iter() {
        let name = k.str()?.to_string();
        let value = constant_text(&v)?;
        checks::constant(&loaded, &name, &value)
            .map_err(|e| PyValueError::new_err(format!("constants['{name}']: {e}")))?;
    }
    Ok(())
}

/// `bvh=value`: `auto`, `cwbvh` or `bvh2`.
pub fn bvh(value: &str) -> PyResult<BvhChoice> {
    BvhChoice::parse(value).map_err(|e| PyValueError::new_err(format!("bvh='{value}': {e}")))
}

/// A constant's value as `--set` takes it (booleans as true/false).
pub fn constant_text(v: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(match v.cast::<PyBool>() {
        Ok(b) => b.is_true().to_string(),
        Err(_) => v.str()?.to_string(),
    })
}
