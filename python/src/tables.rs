//! What a comparison, a study or a verification wrote, read back for Python: its CSV tables
//! as pandas DataFrames (dicts of numpy arrays without pandas) and its EXR images as numpy
//! arrays keyed by the run's label.

use crate::{array, err};
use ::lightgraph::output::read_exr;
use anyhow::Context;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

/// The fields of one CSV line; a field in double quotes may hold commas (and `""` for `"`).
fn fields(line: &str) -> Vec<String> {
    let (mut out, mut field, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    out.push(field);
    out
}

/// The columns of the CSV file at `path`: each column's name and its values as text.
fn columns(path: &Path) -> anyhow::Result<Vec<(String, Vec<String>)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text.lines().filter(|l| !l.is_empty());
    let header = fields(lines.next().with_context(|| format!("{}: empty", path.display()))?);
    let mut columns: Vec<(String, Vec<String>)> = header.into_iter().map(|h| (h, Vec::new())).collect();
    for (i, line) in lines.enumerate() {
        let row = fields(line);
        if row.len() != columns.len() {
            anyhow::bail!(
                "{}: row {} has {} fields, the header {}",
                path.display(),
                i + 2,
                row.len(),
                columns.len()
            );
        }
        for (column, value) in columns.iter_mut().zip(row) {
            column.1.push(value);
        }
    }
    Ok(columns)
}

/// A column as a numpy array: float64 when every value is a number (an empty one NaN) and
/// one is given, text otherwise.
fn column<'py>(py: Python<'py>, values: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
    let number = |v: &str| match v {
        "" => Some(f64::NAN),
        _ => v.parse::<f64>().ok(),
    };
    let numbers: Option<Vec<f64>> = values.iter().map(|v| number(v)).collect();
    match numbers {
        Some(n) if values.iter().any(|v| !v.is_empty()) => Ok(PyArray1::from_vec(py, n).into_any()),
        _ => py.import("numpy")?.call_method1("asarray", (values,)),
    }
}

/// The CSV table at `path` as a pandas DataFrame, or a dict of numpy arrays (column name to
/// values) where pandas is not installed.
pub fn table<'py>(py: Python<'py>, path: &Path) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    for (name, values) in columns(path).map_err(err)? {
        d.set_item(name, column(py, values)?)?;
    }
    match py.import("pandas") {
        Ok(pandas) => pandas.call_method1("DataFrame", (d,)),
        Err(_) => Ok(d.into_any()),
    }
}

/// The EXR images in `dir` (not its subfolders) as float32 arrays of shape (height, width, 3),
/// keyed by the run or estimator they hold (their file name without `.exr` when they say
/// neither).
pub fn images<'py>(py: Python<'py>, dir: &Path) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let listed = std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()));
    let mut paths: Vec<_> = listed
        .map_err(err)?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .collect();
    paths.sort();
    for path in paths {
        let file = read_exr(&path).map_err(err)?;
        let (r, g, b) = (
            file.channel("R", &path),
            file.channel("G", &path),
            file.channel("B", &path),
        );
        let (r, g, b) = (r.map_err(err)?, g.map_err(err)?, b.map_err(err)?);
        let mean: Vec<[f32; 3]> = (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect();
        let stem = path.file_stem().unwrap_or_default().to_string_lossy().to_string();
        let key = ["run", "estimator"]
            .iter()
            .find_map(|k| file.metadata.get(*k).cloned())
            .unwrap_or(stem);
        d.set_item(key, array(py, &mean, file.size)?)?;
    }
    Ok(d)
}
