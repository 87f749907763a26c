//! What `render` and `reference` share about their film: where it goes (always an EXR, never
//! over an existing film unless asked), resuming one (`--resume`: the settings it was made
//! with), and stopping on a signal with the work kept.

use super::args::{Common, GraphArg};
use anyhow::{Result, bail};
use lightgraph::interrupt::{Interrupted, requested};
use lightgraph::reference::Reference;
use std::path::Path;

/// Checks the film's path `out` before any work: it must be an EXR (the PNG preview goes beside
/// it), and an existing file is replaced only with `--force`, or added to with `--resume`.
pub fn check_out(out: &Path, force: bool, resume: Option<&Path>) -> Result<()> {
    let is_exr = out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        bail!(
            "--out {}: the film is an EXR (the PNG preview is written beside it): give a path ending in .exr, e.g. --out {}",
            out.display(),
            out.with_extension("exr").display()
        );
    }
    let resuming_it = resume.is_some_and(|r| same_file(r, out));
    if out.exists() && !force && !resuming_it {
        bail!(
            "--out {}: the file exists; give --resume {0} to add frames to it, --force to replace it, or another --out",
            out.display()
        );
    }
    Ok(())
}

/// Whether `a` and `b` name the same file (by their canonical paths where they exist).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// Fills the settings a resumed film has and the command line does not give: scene, graph,
/// resolution, samples per frame, seed (default `default_seed`) and constants (the measured
/// ones too, so the resumed run renders the film's estimator). Those given must match the
/// film's; the caller checks them with [`Reference::check_settings`].
pub fn settings_from_film(
    common: &mut Common,
    graph: &mut GraphArg,
    seed: &mut Option<u32>,
    default_seed: u32,
    film: &Reference,
) {
    let info = |k: &str| film.info.get(k).cloned().unwrap_or_default();
    common.scene.get_or_insert_with(|| info("scene"));
    graph.graph.get_or_insert_with(|| info("graph"));
    common.res.get_or_insert(film.size);
    common
        .spp
        .get_or_insert_with(|| info("samples_per_frame").parse().unwrap_or(1));
    seed.get_or_insert_with(|| info("seed").parse().unwrap_or(default_seed));
    if common.set.is_empty() && common.max_path_length.is_none() {
        let words = format!("{} {}", info("constants"), info("measured"));
        common.set = words.split_whitespace().map(String::from).collect();
    }
}

/// The frames a run of `total` frames still has to render when its film holds `held`.
pub fn frames_left(total: u32, held: u64, path: Option<&Path>) -> Result<u32> {
    match u64::from(total).checked_sub(held) {
        Some(left) => Ok(left as u32),
        None => bail!(
            "{}: the film holds {held} frames, more than --frames {total} (with --resume, --frames is the run's total)",
            path.map_or_else(String::new, |p| p.display().to_string())
        ),
    }
}

/// After a run wrote `what`: an [`Interrupted`] error if a signal stopped it (so the command
/// exits with the signal's status), else Ok.
pub fn stopped_by_signal(what: String) -> Result<()> {
    match requested() {
        Some(signal) => Err(Interrupted { signal, what }.into()),
        None => Ok(()),
    }
}
