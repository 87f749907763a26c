//! Resuming a comparison: its folder keeps its settings (`settings.txt`, one `key: value` a
//! line), which a resumed comparison must share, and its finished runs' curves
//! (`curves.csv`, rewritten after every run), which it does not render again.

use super::{ErrorSample, RunCurve, paths_per_second};
use crate::metrics::ImageError;
use crate::output::{Output, check_outputs};
use anyhow::{Context, Result, bail};
use std::path::Path;

/// The settings file of a comparison's folder.
pub const SETTINGS_FILE: &str = "settings.txt";

/// Settings as `key: value` lines.
fn settings_text(settings: &[(String, String)]) -> String {
    settings.iter().map(|(k, v)| format!("{k}: {v}\n")).collect()
}

/// Writes `settings` into `dir`'s settings file.
pub fn write_settings(dir: &Path, settings: &[(String, String)]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(SETTINGS_FILE);
    std::fs::write(&path, settings_text(settings)).with_context(|| format!("writing {}", path.display()))
}

/// Checks the folder `dir` of a comparison (or a study) before any work: writable, and
/// holding no earlier one unless `force` or `resume` (which continues it).
pub fn check_folder(dir: &Path, force: bool, resume: bool) -> Result<()> {
    let entries = [
        SETTINGS_FILE,
        "curves.csv",
        "summary.md",
        "summary.csv",
        "rmse_vs_time.png",
        "report.html",
    ];
    check_outputs(
        &[Output::Folder(dir, &entries)],
        force || resume,
        Some("--resume to continue it"),
    )
}

/// Whether `dir` holds a comparison to resume.
pub fn resumable(dir: &Path) -> bool {
    dir.join(SETTINGS_FILE).is_file()
}

/// Checks that the comparison (or study) in `dir` was made with `settings`: an error naming
/// the first setting that differs, or saying there is nothing to resume.
pub fn check_settings(dir: &Path, settings: &[(String, String)]) -> Result<()> {
    let path = dir.join(SETTINGS_FILE);
    let Ok(text) = std::fs::read_to_string(&path) else {
        bail!(
            "--resume: {} holds nothing to resume ({} is missing)",
            dir.display(),
            path.display()
        );
    };
    let before: Vec<(&str, &str)> = text.lines().filter_map(|l| l.split_once(": ")).collect();
    let now: Vec<(&str, &str)> = settings.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    for i in 0..before.len().max(now.len()) {
        let (old, new) = (before.get(i), now.get(i));
        if old != new {
            let describe = |s: Option<&(&str, &str)>| s.map_or("nothing".to_string(), |(k, v)| format!("{k} '{v}'"));
            bail!(
                "--resume: {} was made with {}, this run has {}: resume with the same settings, or give \
                 another --out",
                path.display(),
                describe(old),
                describe(new)
            );
        }
    }
    Ok(())
}

/// The runs whose curves `dir/curves.csv` holds (none when there is no such file), in its
/// order, of an image of `pixels` pixels.
pub fn finished_runs(dir: &Path, pixels: usize) -> Result<Vec<RunCurve>> {
    let path = dir.join("curves.csv");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    let mut runs: Vec<RunCurve> = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let (label, setup_seconds, sample) =
            parse_row(line).with_context(|| format!("{} line {}: '{line}'", path.display(), n + 1))?;
        match runs.last_mut() {
            Some(run) if run.label == label => run.samples.push(sample),
            _ => runs.push(RunCurve {
                label: label.to_string(),
                setup_seconds,
                samples: vec![sample],
                samples_per_second: 0.0,
            }),
        }
    }
    for run in &mut runs {
        run.samples_per_second = paths_per_second(&run.samples, pixels);
    }
    Ok(runs)
}

/// One row of `curves.csv`: the run's label, its set-up seconds and the error sample.
fn parse_row(line: &str) -> Result<(&str, f64, ErrorSample)> {
    let fields: Vec<&str> = line.split(',').collect();
    let [
        label,
        seconds,
        setup,
        frames,
        spp,
        mse,
        rmse,
        rel_mse,
        non_finite,
        _floor,
    ] = fields[..]
    else {
        bail!("expected 10 fields, found {}", fields.len());
    };
    let sample = ErrorSample {
        seconds: seconds.parse()?,
        frames: frames.parse()?,
        samples_per_pixel: spp.parse()?,
        error: ImageError {
            mse: mse.parse()?,
            rmse: rmse.parse()?,
            rel_mse: rel_mse.parse()?,
            non_finite: non_finite.parse()?,
        },
    };
    Ok((label, setup.parse()?, sample))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn settings_must_match_to_resume_and_curves_read_back() {
        let dir = std::env::temp_dir().join(format!("lightgraph-compare-resume-{}", std::process::id()));
        std::fs::remove_dir_all(&dir).ok();
        let given = settings(&[("scene", "box"), ("time", "3s")]);
        let e = check_settings(&dir, &given).unwrap_err().to_string();
        assert!(e.contains("holds nothing to resume"), "{e}");
        assert!(!resumable(&dir));
        write_settings(&dir, &given).unwrap();
        assert!(resumable(&dir));
        check_settings(&dir, &given).unwrap();
        let e = check_settings(&dir, &settings(&[("scene", "box"), ("time", "4s")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("time '3s'") && e.contains("time '4s'"), "{e}");
        let e = check_settings(&dir, &settings(&[("scene", "box")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("has nothing"), "{e}");
        assert!(finished_runs(&dir, 4).unwrap().is_empty());
        let header =
            "run,seconds,setup_seconds,frames,samples_per_pixel,mse,rmse,rel_mse,non_finite_pixels,reference_floor_mse";
        let rows = [
            "pt:A,0.5,0.2,1,2,4e-2,2e-1,1e-1,0,0e0",
            "pt:A,1.0,0.2,3,6,1e-2,1e-1,5e-2,0,0e0",
            "pt:B,1.0,0.3,2,4,1e-2,1e-1,5e-2,1,0e0",
        ];
        std::fs::write(dir.join("curves.csv"), format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        let runs = finished_runs(&dir, 4).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(
            (runs[0].label.as_str(), runs[0].samples.len(), runs[0].setup_seconds),
            ("pt:A", 2, 0.2)
        );
        // 6 samples per pixel of 4 pixels in 1 s.
        assert_eq!(runs[0].samples_per_second, 24.0);
        assert_eq!((runs[1].last().frames, runs[1].last().error.non_finite), (2, 1));
        std::fs::write(dir.join("curves.csv"), format!("{header}\npt:A,x\n")).unwrap();
        let e = format!("{:#}", finished_runs(&dir, 4).unwrap_err());
        std::fs::remove_dir_all(&dir).ok();
        assert!(e.contains("line 2") && e.contains("expected 10 fields"), "{e}");
    }
}
