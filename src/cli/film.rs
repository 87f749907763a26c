//! What `render` and `reference` share about their film: resuming one (`--resume`: the
//! settings it was made with) and the frames left of a run.

use super::args::{Common, GraphArg};
use anyhow::{Result, bail};
use lightgraph::film::Film;
use std::path::Path;

/// Fills the settings a resumed film has and the command line does not give
/// ([`lightgraph::run::RunOptions::from_film`]).
pub fn settings_from_film(
    common: &mut Common,
    graph: &mut GraphArg,
    seed: &mut Option<u32>,
    default_seed: u32,
    film: &Film,
) {
    let mut options = common.run_options();
    options.from_film(&mut graph.graph, seed, default_seed, film);
    common.take(options);
}

/// The frames a run of `total` frames still has to render when its film holds `held`.
pub fn frames_left(total: u32, held: u64, path: Option<&Path>) -> Result<u32> {
    match u64::from(total).checked_sub(held) {
        Some(left) => Ok(left as u32),
        None => bail!(
            "{}: the film holds {held} frames, more than --frames {total} (with --resume, --frames is the run's total, 64 when not given): give a larger --frames, or --time",
            path.map_or_else(String::new, |p| p.display().to_string())
        ),
    }
}
