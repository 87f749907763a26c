//! Choosing an estimator's layout by measurement: each layout of the graph renders the
//! scene briefly (after a warm-up frame, so pipeline creation and the first frame are off the
//! clock) and the one with the most camera samples per second runs in the study.

use crate::bench::measure;
use crate::render::{LoadedScene, SessionOptions};
use anyhow::{Result, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{Gpu, Graph};
use std::time::Duration;

/// One layout's measured rate on a scene, or why it could not be measured.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutRate {
    /// Layout name.
    pub layout: String,
    /// Camera samples (paths) per second, wall-clock; the error when the layout failed.
    pub samples_per_second: Result<f64, String>,
}

/// How an estimator's layout was chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum LayoutChoice {
    /// Named (`graph:Layout`).
    Named,
    /// The fastest of the graph's layouts, measured on the scene: every layout's rate.
    Measured(Vec<LayoutRate>),
}

/// One layout to measure: its name, its declaration and the scene loaded with its BVH.
pub type Candidate<'a> = (&'a str, &'a LayoutDecl, &'a LoadedScene);

/// Measures each candidate layout of `graph` with `options` for `budget` (after a warm-up
/// frame); `progress` sees each rate as it is measured. A layout that fails is recorded with
/// its error, not returned as one.
pub fn measure_layouts(
    gpu: &Gpu,
    graph: &Graph,
    candidates: &[Candidate],
    options: &SessionOptions,
    budget: Duration,
    mut progress: impl FnMut(&LayoutRate),
) -> Vec<LayoutRate> {
    candidates
        .iter()
        .map(|&(layout, decl, scene)| {
            let measured = measure(gpu, graph, layout, decl.clone(), scene, options.clone(), budget);
            let rate = LayoutRate {
                layout: layout.to_string(),
                samples_per_second: measured.map(|m| m.samples_per_second()).map_err(|e| format!("{e:#}")),
            };
            progress(&rate);
            rate
        })
        .collect()
}

/// The layout with the most samples per second; an error listing why each failed when none
/// could be measured.
pub fn fastest(rates: &[LayoutRate]) -> Result<&LayoutRate> {
    let measured = rates
        .iter()
        .filter_map(|r| r.samples_per_second.as_ref().ok().map(|&s| (r, s)));
    match measured.max_by(|a, b| a.1.total_cmp(&b.1)) {
        Some((rate, _)) => Ok(rate),
        None => {
            let failures: Vec<String> = rates
                .iter()
                .map(|r| {
                    format!(
                        "{}: {}",
                        r.layout,
                        r.samples_per_second.as_ref().err().map_or("", |e| e)
                    )
                })
                .collect();
            bail!("no layout could be measured ({})", failures.join("; "))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rate(layout: &str, r: Result<f64, &str>) -> LayoutRate {
        LayoutRate {
            layout: layout.into(),
            samples_per_second: r.map_err(String::from),
        }
    }

    #[test]
    fn the_fastest_measured_layout_is_chosen_and_failures_are_named() {
        let rates = [rate("A", Ok(2e6)), rate("B", Err("out of memory")), rate("C", Ok(3e6))];
        assert_eq!(fastest(&rates).unwrap().layout, "C");
        let failed = [rate("A", Err("too big")), rate("B", Err("lost"))];
        let e = fastest(&failed).unwrap_err().to_string();
        assert!(e.contains("A: too big") && e.contains("B: lost"), "{e}");
        assert!(fastest(&[]).is_err());
    }
}
