//! Choosing an estimator's layout by measurement: each layout of the graph renders the
//! scene briefly (after a warm-up frame, so pipeline creation and the first frame are off the
//! clock) and the one with the most camera samples per second runs in the study.

use crate::bench::measure;
use crate::run::Run;
use anyhow::{Result, bail};
use lightgraph_engine::Gpu;
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

/// Measures each candidate run (one layout of a graph each, with the scene loaded with its
/// BVH) for `budget` (after a warm-up frame); `progress` sees each rate as it is measured. A
/// layout that fails is recorded with its error, not returned as one.
pub fn measure_layouts(
    gpu: &Gpu,
    candidates: &[Run],
    budget: Duration,
    mut progress: impl FnMut(&LayoutRate),
) -> Vec<LayoutRate> {
    candidates
        .iter()
        .map(|run| {
            let measured = measure(gpu, run, budget);
            let rate = LayoutRate {
                layout: run.layout.clone(),
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

/// Each estimator's layout and how it was chosen, as `choices_text` writes them into a
/// scene's folder so that a resumed study runs the layouts it chose before.
pub type Choices = Vec<(String, String, LayoutChoice)>;

/// `choices` as text, one estimator a line, tab-separated: the estimator, its layout, and
/// `named` or `measured` followed by each measured layout as `name=rate` or `name!error`.
pub fn choices_text(choices: &[(String, String, LayoutChoice)]) -> String {
    let mut text = String::new();
    for (estimator, layout, choice) in choices {
        let how = match choice {
            LayoutChoice::Named => "named".to_string(),
            LayoutChoice::Measured(rates) => std::iter::once("measured".to_string())
                .chain(rates.iter().map(|r| match &r.samples_per_second {
                    Ok(v) => format!("{}={v:e}", r.layout),
                    Err(e) => format!("{}!{}", r.layout, e.replace(['\t', '\n'], " ")),
                }))
                .collect::<Vec<_>>()
                .join("\t"),
        };
        text.push_str(&format!("{estimator}\t{layout}\t{how}\n"));
    }
    text
}

/// The choices [`choices_text`] wrote.
pub fn parse_choices(text: &str) -> Result<Choices> {
    text.lines()
        .map(|line| {
            let mut fields = line.split('\t');
            let (Some(estimator), Some(layout), Some(how)) = (fields.next(), fields.next(), fields.next()) else {
                bail!("'{line}' is not estimator, layout and how it was chosen");
            };
            let choice = match how {
                "named" => LayoutChoice::Named,
                "measured" => LayoutChoice::Measured(fields.map(parse_rate).collect::<Result<_>>()?),
                other => bail!("'{other}' is neither 'named' nor 'measured'"),
            };
            Ok((estimator.to_string(), layout.to_string(), choice))
        })
        .collect()
}

/// A measured layout as `name=rate` or `name!error`.
fn parse_rate(field: &str) -> Result<LayoutRate> {
    let (layout, rate) = match (field.split_once('='), field.split_once('!')) {
        (Some((layout, rate)), _) => (layout, Ok(rate.parse::<f64>()?)),
        (None, Some((layout, error))) => (layout, Err(error.to_string())),
        (None, None) => bail!("'{field}' is neither name=rate nor name!error"),
    };
    Ok(LayoutRate {
        layout: layout.to_string(),
        samples_per_second: rate,
    })
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

    #[test]
    fn choices_read_back_as_written() {
        let choices = vec![
            (
                "pt".to_string(),
                "C".to_string(),
                LayoutChoice::Measured(vec![
                    rate("A", Ok(2.5e6)),
                    rate("B", Err("out of\tmemory\nat all")),
                    rate("C", Ok(3e6)),
                ]),
            ),
            (
                "ppm:PPMsk@PM_ALPHA=1".to_string(),
                "PPMsk".to_string(),
                LayoutChoice::Named,
            ),
        ];
        let back = parse_choices(&choices_text(&choices)).unwrap();
        assert_eq!(back[1], choices[1]);
        assert_eq!((&back[0].0, &back[0].1), (&choices[0].0, &choices[0].1));
        let LayoutChoice::Measured(rates) = &back[0].2 else {
            panic!("{back:?}");
        };
        assert_eq!(rates[0], rate("A", Ok(2.5e6)));
        assert_eq!(rates[1], rate("B", Err("out of memory at all")));
        let e = parse_choices("pt\tA\tguessed\n").unwrap_err().to_string();
        assert!(e.contains("'guessed'"), "{e}");
        assert!(parse_choices("pt\n").is_err());
    }
}
