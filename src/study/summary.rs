//! A study's summary: per scene, each estimator's time to the best final error of the set
//! (the smallest RMSE any of them reached at the end of its budget) and the winner or the
//! tie ([`super::verdict`]); written as `summary.md`, `summary.csv` and `layouts.csv`.

use super::layouts::LayoutChoice;
use super::verdict::{Outcome, TIE_STANDARD_ERRORS, Verdict, verdict};
use crate::compare::{ErrorSample, RunBudget};
use anyhow::{Context, Result};
use std::fmt::Write;
use std::path::Path;
use std::time::Duration;

/// One estimator's run on one scene.
#[derive(Debug, Clone)]
pub struct EstimatorRun {
    /// The estimator as `--estimators` names it (`pt`, `bpt-lvc:LVC-BPTmk`, ...).
    pub estimator: String,
    /// The layout it ran in.
    pub layout: String,
    /// Its label in the scene's comparison (`graph:layout`), which names its images.
    pub label: String,
    /// How that layout was chosen.
    pub choice: LayoutChoice,
    /// Its error against time (a comparison's curve).
    pub samples: Vec<ErrorSample>,
}

/// Where a scene's reference came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceSource {
    /// It was there with the samples asked for, and used as it was.
    Given,
    /// It was there with fewer samples than asked for, and samples were added.
    Resumed,
    /// The study rendered it.
    Rendered,
}

/// What the summary says about a scene's reference.
#[derive(Debug, Clone)]
pub struct ReferenceNote {
    /// The reference file.
    pub path: String,
    /// The graph that rendered it.
    pub graph: String,
    /// Samples per pixel.
    pub samples_per_pixel: u64,
    /// Render seconds spent on it.
    pub seconds: f64,
    /// Its own noise: the RMSE it adds to every error measured against it.
    pub noise_rmse: f64,
    /// Where it came from.
    pub source: ReferenceSource,
}

/// One scene of a study: its runs in the order of the estimators.
#[derive(Debug, Clone)]
pub struct SceneRuns {
    /// The scene as `--scenes` names it.
    pub scene: String,
    /// The folder of its comparison below the study's.
    pub folder: String,
    /// Its reference.
    pub reference: ReferenceNote,
    /// Each estimator's run.
    pub runs: Vec<EstimatorRun>,
}

impl SceneRuns {
    /// The verdict on this scene's runs.
    pub fn verdict(&self) -> Verdict {
        let curves: Vec<&[ErrorSample]> = self.runs.iter().map(|r| r.samples.as_slice()).collect();
        verdict(&curves)
    }
}

/// What the summary says about the study besides its scenes.
pub struct StudyContext<'a> {
    /// GPU description.
    pub device: &'a str,
    /// Budget of each run.
    pub budget: RunBudget,
    /// Time each layout was measured for when a layout was chosen by measurement.
    pub layout_time: Duration,
    /// The estimators, in the order of the table's columns.
    pub estimators: &'a [String],
    /// The scenes asked for (the summary may hold fewer: those done so far).
    pub scene_count: usize,
}

/// Writes `summary.md`, `summary.csv` and `layouts.csv` into `dir`; returns the Markdown.
pub fn write_summary(dir: &Path, ctx: &StudyContext, scenes: &[SceneRuns]) -> Result<String> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let md = markdown(ctx, scenes)?;
    for (name, text) in [
        ("summary.md", md.clone()),
        ("summary.csv", summary_csv(scenes)?),
        ("layouts.csv", layouts_csv(scenes)?),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(md)
}

/// The winner or the tie as the Markdown table writes it (`—` for neither).
fn outcome_text(scene: &SceneRuns, outcome: &Outcome) -> String {
    match outcome {
        Outcome::Nobody => "—".to_string(),
        Outcome::Winner(i) => format!("**{}**", scene.runs[*i].estimator),
        Outcome::Tie(runs) => {
            let names: Vec<&str> = runs.iter().map(|&i| scene.runs[i].estimator.as_str()).collect();
            format!("tie: {}", names.join(", "))
        }
    }
}

/// RMSE as the tables write it.
fn rmse_text(rmse: Option<f64>) -> String {
    rmse.map_or("—".to_string(), |e| format!("{e:.4e}"))
}

/// A time as the tables write it.
fn time_text(seconds: Option<f64>) -> String {
    seconds.map_or("—".to_string(), |t| format!("{t:.3}"))
}

/// The run of `estimator` on `scene`, if it has one.
fn run_of<'a>(scene: &'a SceneRuns, estimator: &str) -> Option<(usize, &'a EstimatorRun)> {
    scene.runs.iter().enumerate().find(|(_, r)| r.estimator == estimator)
}

fn markdown(ctx: &StudyContext, scenes: &[SceneRuns]) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "# Study: {} scenes × {} estimators\n",
        ctx.scene_count,
        ctx.estimators.len()
    )?;
    if scenes.len() < ctx.scene_count {
        writeln!(s, "**{} of {} scenes done so far.**\n", scenes.len(), ctx.scene_count)?;
    }
    writeln!(s, "- device: {}", ctx.device)?;
    writeln!(s, "- budget: {} per estimator and scene", ctx.budget.describe())?;
    writeln!(
        s,
        "- layouts: as named (`graph:Layout`), else the most samples per second of the graph's \
         layouts, each measured on the scene for {:?} after a warm-up frame",
        ctx.layout_time
    )?;
    writeln!(
        s,
        "- target per scene: the best final RMSE of the set, the smallest any estimator reached at \
         the end of its budget; each estimator's time is when its curve reached it **and stayed at \
         or below it** to the end (interpolated log-log between error samples; a dip below it that \
         comes back up does not count), — where its curve ended above it"
    )?;
    writeln!(
        s,
        "- winner: the first to reach the target, so it has the best final RMSE; a **tie** where \
         other estimators' times (extrapolated at the Monte Carlo rate, time ∝ RMSE⁻², for those \
         that ended above the target) are within {TIE_STANDARD_ERRORS} standard errors of the \
         first's, from each run's noise: the relative scatter of its log RMSE from sample to sample \
         over the last 1.5 decades of its curve (the ± of the final RMSE table), doubled in log time\n"
    )?;
    time_table(&mut s, ctx, scenes)?;
    final_table(&mut s, ctx, scenes)?;
    layout_table(&mut s, scenes)?;
    reference_list(&mut s, scenes)?;
    Ok(s)
}

/// The table of the issue: per scene, each estimator's time to the best final error and the
/// winner.
fn time_table(s: &mut String, ctx: &StudyContext, scenes: &[SceneRuns]) -> Result<()> {
    writeln!(s, "## Time to the best final error [s]\n")?;
    writeln!(
        s,
        "| scene | best final RMSE | {} | winner |",
        ctx.estimators.join(" | ")
    )?;
    writeln!(s, "|---|---:|{}---|", "---:|".repeat(ctx.estimators.len()))?;
    for scene in scenes {
        let v = scene.verdict();
        let times: Vec<String> = ctx
            .estimators
            .iter()
            .map(|e| time_text(run_of(scene, e).and_then(|(i, _)| v.time_to_best[i])))
            .collect();
        let winner = outcome_text(scene, &v.outcome);
        writeln!(
            s,
            "| [{}]({}/summary.md) | {} | {} | {winner} |",
            scene.scene,
            scene.folder,
            rmse_text(v.best_final_rmse),
            times.join(" | ")
        )?;
    }
    Ok(())
}

/// Per scene, each estimator's RMSE at the end of its budget.
fn final_table(s: &mut String, ctx: &StudyContext, scenes: &[SceneRuns]) -> Result<()> {
    writeln!(s, "\n## Final RMSE (± its noise)\n")?;
    writeln!(s, "| scene | {} |", ctx.estimators.join(" | "))?;
    writeln!(s, "|---|{}", "---:|".repeat(ctx.estimators.len()))?;
    for scene in scenes {
        let v = scene.verdict();
        let finals: Vec<String> = ctx
            .estimators
            .iter()
            .map(|e| {
                let Some((i, run)) = run_of(scene, e) else {
                    return rmse_text(None);
                };
                let noise = v.noise[i].map_or(String::new(), |n| format!(" ± {:.1}%", 100.0 * n));
                format!("{}{noise}", rmse_text(run.samples.last().map(|l| l.error.rmse)))
            })
            .collect();
        writeln!(s, "| {} | {} |", scene.scene, finals.join(" | "))?;
    }
    Ok(())
}

/// Per scene and estimator, the layout that ran and, where it was measured, every layout's
/// rate.
fn layout_table(s: &mut String, scenes: &[SceneRuns]) -> Result<()> {
    writeln!(s, "\n## Layouts\n")?;
    writeln!(
        s,
        "| scene | estimator | layout | chosen by | Msamples/s of each layout |"
    )?;
    writeln!(s, "|---|---|---|---|---|")?;
    for scene in scenes {
        for run in &scene.runs {
            let (how, rates) = match &run.choice {
                LayoutChoice::Named => ("named", String::new()),
                LayoutChoice::Measured(rates) => {
                    let each: Vec<String> = rates
                        .iter()
                        .map(|r| match &r.samples_per_second {
                            Ok(v) => format!("{} {:.3}", r.layout, v / 1e6),
                            Err(_) => format!("{} failed", r.layout),
                        })
                        .collect();
                    ("measurement", each.join(", "))
                }
            };
            writeln!(
                s,
                "| {} | {} | {} | {how} | {rates} |",
                scene.scene, run.estimator, run.layout
            )?;
        }
    }
    Ok(())
}

/// Each scene's reference, with a warning where its own noise is more than half the target.
fn reference_list(s: &mut String, scenes: &[SceneRuns]) -> Result<()> {
    writeln!(s, "\n## References\n")?;
    for scene in scenes {
        let r = &scene.reference;
        let source = match r.source {
            ReferenceSource::Given => "given",
            ReferenceSource::Resumed => "resumed",
            ReferenceSource::Rendered => "rendered",
        };
        writeln!(
            s,
            "- {}: `{}` ({source}): graph {}, {} spp in {:.1} s; its own noise is RMSE {:.3e}",
            scene.scene, r.path, r.graph, r.samples_per_pixel, r.seconds, r.noise_rmse
        )?;
        if scene
            .verdict()
            .best_final_rmse
            .is_some_and(|best| r.noise_rmse > 0.5 * best)
        {
            writeln!(
                s,
                "  - **Warning**: more than half the best final RMSE; give it more time \
                 (`--reference-time`, it resumes) before trusting this scene's numbers."
            )?;
        }
    }
    Ok(())
}

/// One row per scene and estimator: its layout, final error and its noise, time to the best
/// final error of the set, and the scene's winner (or `tie: a; b`).
fn summary_csv(scenes: &[SceneRuns]) -> Result<String> {
    let mut csv = String::from(
        "scene,estimator,layout,layout_chosen_by,final_seconds,final_spp,final_rmse,final_rmse_noise,best_final_rmse,time_to_best_s,winner\n",
    );
    for scene in scenes {
        let v = scene.verdict();
        let winner = match &v.outcome {
            Outcome::Nobody => String::new(),
            Outcome::Winner(i) => scene.runs[*i].estimator.clone(),
            Outcome::Tie(runs) => {
                let names: Vec<&str> = runs.iter().map(|&i| scene.runs[i].estimator.as_str()).collect();
                format!("tie: {}", names.join("; "))
            }
        };
        for ((run, time), noise) in scene.runs.iter().zip(&v.time_to_best).zip(&v.noise) {
            let last = run.samples.last();
            let how = match run.choice {
                LayoutChoice::Named => "named",
                LayoutChoice::Measured(_) => "measurement",
            };
            writeln!(
                csv,
                "{},{},{},{how},{},{},{},{},{},{},{winner}",
                scene.scene,
                run.estimator,
                run.layout,
                last.map_or(String::new(), |l| format!("{:.6}", l.seconds)),
                last.map_or(String::new(), |l| l.samples_per_pixel.to_string()),
                last.map_or(String::new(), |l| format!("{:e}", l.error.rmse)),
                noise.map_or(String::new(), |n| format!("{n:e}")),
                v.best_final_rmse.map_or(String::new(), |b| format!("{b:e}")),
                time.map_or(String::new(), |t| format!("{t:.6}")),
            )?;
        }
    }
    Ok(csv)
}

/// One row per measured layout: its rate (empty and the error when it failed) and whether
/// it was chosen.
fn layouts_csv(scenes: &[SceneRuns]) -> Result<String> {
    let mut csv = String::from("scene,estimator,layout,samples_per_second,chosen,error\n");
    for scene in scenes {
        for run in &scene.runs {
            let LayoutChoice::Measured(rates) = &run.choice else {
                continue;
            };
            for r in rates {
                let (rate, error) = match &r.samples_per_second {
                    Ok(v) => (format!("{v:e}"), String::new()),
                    Err(e) => (String::new(), format!("\"{}\"", e.replace('"', "'").replace('\n', " "))),
                };
                writeln!(
                    csv,
                    "{},{},{},{rate},{},{error}",
                    scene.scene,
                    run.estimator,
                    r.layout,
                    r.layout == run.layout
                )?;
            }
        }
    }
    Ok(csv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::curve;
    use crate::study::layouts::LayoutRate;

    fn scene(name: &str, runs: Vec<EstimatorRun>) -> SceneRuns {
        SceneRuns {
            scene: name.into(),
            folder: name.into(),
            reference: ReferenceNote {
                path: format!("refs/{name}.exr"),
                graph: "vcm".into(),
                samples_per_pixel: 64,
                seconds: 2.0,
                noise_rmse: 0.09,
                source: ReferenceSource::Rendered,
            },
            runs,
        }
    }

    fn run(estimator: &str, layout: &str, choice: LayoutChoice, points: &[(f64, f64)]) -> EstimatorRun {
        EstimatorRun {
            estimator: estimator.into(),
            layout: layout.into(),
            label: format!("{estimator}:{layout}"),
            choice,
            samples: curve(points),
        }
    }

    #[test]
    fn the_summary_files_name_every_scene_estimator_layout_and_winner() {
        let measured = LayoutChoice::Measured(vec![
            LayoutRate {
                layout: "A".into(),
                samples_per_second: Ok(2e6),
            },
            LayoutRate {
                layout: "B".into(),
                samples_per_second: Err("no \"memory\"\nat all".into()),
            },
        ]);
        let scenes = [
            scene(
                "s1",
                vec![
                    run("pt", "A", measured, &[(1.0, 1.0), (10.0, 0.1)]),
                    run("ppm:X", "X", LayoutChoice::Named, &[(1.0, 0.3), (10.0, 0.2)]),
                ],
            ),
            scene(
                "s2",
                vec![
                    run("pt", "A", LayoutChoice::Named, &[(1.0, 0.3), (10.0, 0.2)]),
                    run("ppm:X", "X", LayoutChoice::Named, &[(1.0, 0.3), (10.0, 0.1)]),
                ],
            ),
            // Equal curves: a tie.
            scene(
                "s3",
                vec![
                    run("pt", "A", LayoutChoice::Named, &[(1.0, 0.3), (10.0, 0.1)]),
                    run("ppm:X", "X", LayoutChoice::Named, &[(1.0, 0.3), (10.0, 0.1)]),
                ],
            ),
        ];
        let estimators = ["pt".to_string(), "ppm:X".into()];
        let ctx = StudyContext {
            device: "GPU",
            budget: RunBudget {
                time: Duration::from_secs(10),
                setup_on_clock: false,
            },
            layout_time: Duration::from_millis(500),
            estimators: &estimators,
            scene_count: 4,
        };
        let dir = std::env::temp_dir().join(format!("lightgraph-study-summary-{}", std::process::id()));
        let md = write_summary(&dir, &ctx, &scenes).unwrap();
        let csv = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
        let layouts = std::fs::read_to_string(dir.join("layouts.csv")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert!(md.contains("**3 of 4 scenes done so far.**"), "{md}");
        assert!(md.contains("| scene | best final RMSE | pt | ppm:X | winner |"), "{md}");
        assert!(
            md.contains("| [s1](s1/summary.md) | 1.0000e-1 | 10.000 | — | **pt** |"),
            "{md}"
        );
        assert!(
            md.contains("| [s2](s2/summary.md) | 1.0000e-1 | — | 10.000 | **ppm:X** |"),
            "{md}"
        );
        assert!(
            md.contains("| [s3](s3/summary.md) | 1.0000e-1 | 10.000 | 10.000 | tie: pt, ppm:X |"),
            "{md}"
        );
        assert!(md.contains("| s1 | pt | A | measurement | A 2.000, B failed |"), "{md}");
        // The references' noise (0.09) is more than half the best error (0.1) in every scene.
        assert_eq!(md.matches("**Warning**").count(), 3, "{md}");
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows.len(), 7, "{csv}");
        // Two samples a curve: too few to tell their noise.
        assert_eq!(rows[1], "s1,pt,A,measurement,10.000000,1,1e-1,,1e-1,10.000000,pt");
        assert_eq!(rows[2], "s1,ppm:X,X,named,10.000000,1,2e-1,,1e-1,,pt");
        assert!(rows[4].ends_with(",ppm:X"), "{csv}");
        assert!(rows[6].ends_with(",tie: pt; ppm:X"), "{csv}");
        let layout_rows: Vec<&str> = layouts.lines().collect();
        assert_eq!(layout_rows[1], "s1,pt,A,2e6,true,");
        assert_eq!(layout_rows[2], "s1,pt,B,,false,\"no 'memory' at all\"");
        assert_eq!(layout_rows.len(), 3, "{layouts}");
    }
}
