//! The reports of `lightgraph verify`: `verify.csv` and `verify.md` (a row per scene and pair
//! of estimators, with the verdict and its numbers), and for every pair that differs a PNG of
//! where: the block t-scores over the image.

use super::stats::{PairTest, TestSettings};
use super::{Gap, Outcome, PairResult, unconfirmed_gaps};
use crate::run::Image;
use anyhow::{Context, Result};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// One run's line in the report: its label and what it rendered.
#[derive(Debug, Clone)]
pub struct RunLine {
    /// The scene.
    pub scene: String,
    /// The estimator.
    pub label: String,
    /// Frames and seconds rendered.
    pub frames: u32,
    /// Seconds.
    pub seconds: f64,
    /// Samples rejected as NaN, Inf or negative.
    pub rejected_samples: u64,
    /// The image mean's light (channel sum) and its relative standard error.
    pub light: (f64, f64),
}

/// The CSV columns, one row per pair.
const CSV_HEADER: &str = "scene,a,b,verdict,outcome,expected_gaps,blocks,blocks_differ,max_block_t,t_critical,light_a,light_b,mean_difference,mean_t,mean_detectable,block_coverage,map,mean_bias_allowance";

/// Writes `verify.csv` and `verify.md` into `out`; returns the Markdown.
pub fn write_tables(out: &Path, settings: &TestSettings, runs: &[RunLine], pairs: &[PairResult]) -> Result<String> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut csv = format!("{CSV_HEADER}\n");
    for p in pairs {
        let t = &p.test;
        let map = map_name(p).map(|m| m.display().to_string()).unwrap_or_default();
        writeln!(
            csv,
            "{},{},{},{},{},\"{}\",{},{},{:.3},{:.3},{:.6e},{:.6e},{:.5},{:.3},{:.5},{:.3},{},{:.5}",
            p.scene,
            p.a,
            p.b,
            t.verdict.word(),
            p.outcome.word(),
            gaps_text(p),
            t.blocks.len(),
            t.blocks_rejected(),
            t.max_block_t(),
            t.t_critical,
            t.light.0,
            t.light.1,
            t.mean_difference,
            t.mean_t,
            t.mean_detectable,
            t.coverage,
            map,
            t.mean_allowance
        )?;
    }
    let csv_path = out.join("verify.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    let md = markdown(settings, runs, pairs);
    let md_path = out.join("verify.md");
    std::fs::write(&md_path, &md).with_context(|| format!("writing {}", md_path.display()))?;
    Ok(md)
}

/// The Markdown report: the test's settings, the runs, and a table per scene.
fn markdown(settings: &TestSettings, runs: &[RunLine], pairs: &[PairResult]) -> String {
    let mut md = String::from("# lightgraph verify\n\n");
    let _ = writeln!(
        md,
        "Block and image-mean Welch tests, Holm-corrected to a family-wise error of {} over the run's {} pairs \
         ({:.2e} a pair); \"agree\" needs the power ({:.0}%) to see a {:.1}% difference of the image mean and a {:.0}% \
         difference in the blocks holding {:.0}% of the light; where a graph declares paths of the scene biased at a finite \
         budget, a difference of {:.1}% (mean) and {:.1}% (block) of their light is allowed on top of the noise \
         (column `bias allowed`; docs/verify.md).\n",
        settings.alpha,
        settings.pairs,
        settings.pair_alpha(),
        settings.power * 100.0,
        settings.detect_mean * 100.0,
        settings.detect_block * 100.0,
        settings.coverage * 100.0,
        settings.bias_tolerance_mean * 100.0,
        settings.bias_tolerance_block * 100.0
    );
    md.push_str(
        "| scene | estimator | frames | seconds | image light | its relative error | rejected samples |\n\
         |---|---|---:|---:|---:|---:|---:|\n",
    );
    for r in runs {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.5} | {:.4} | {} |",
            r.scene, r.label, r.frames, r.seconds, r.light.0, r.light.1, r.rejected_samples
        );
    }
    md.push_str(
        "\n| scene | a | b | verdict | outcome | blocks differing | worst block: t (critical), (a − b)/mean | mean (a − b)/mean | mean t | mean detectable | bias allowed | block coverage | expected gaps |\n\
         |---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for p in pairs {
        let t = &p.test;
        let worst = t.worst_block().map_or(String::new(), |(i, b)| {
            let across = p.grid_width.max(1) as usize;
            format!(
                "({}, {}): {:.1} ({:.1}), {:+.3}",
                i % across,
                i / across,
                b.t,
                t.t_critical,
                b.difference
            )
        });
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {}/{} | {} | {:+.4} | {:.1} | {:.4} | {:.4} | {:.2} | {} |",
            p.scene,
            p.a,
            p.b,
            t.verdict.word(),
            p.outcome.word(),
            t.blocks_rejected(),
            t.blocks.len(),
            worst,
            t.mean_difference,
            t.mean_t,
            t.mean_detectable,
            t.mean_allowance,
            t.coverage,
            gaps_text(p)
        );
    }
    let count = |o: Outcome| pairs.iter().filter(|p| p.outcome == o).count();
    let _ = writeln!(
        md,
        "\n{} pairs: {} as predicted, {} agreeing where a declared gap was not seen, {} differing unexpectedly, {} undecided.",
        pairs.len(),
        count(Outcome::AsPredicted),
        count(Outcome::GapNotSeen),
        count(Outcome::UnexpectedDifference),
        count(Outcome::Undecided)
    );
    let unconfirmed = unconfirmed_gaps(pairs);
    if !unconfirmed.is_empty() {
        let list: Vec<String> = unconfirmed.iter().map(Gap::to_string).collect();
        let _ = writeln!(
            md,
            "\nDeclared gaps no pair showed (a declaration that claims too much, or scenes without such light): {}.",
            list.join("; ")
        );
    }
    md
}

/// A pair's expected gaps, for the tables.
fn gaps_text(p: &PairResult) -> String {
    p.gaps.iter().map(Gap::to_string).collect::<Vec<_>>().join("; ")
}

/// Where the map of a pair that differs is written (relative to the output folder), or
/// `None` when the pair does not differ.
pub fn map_name(p: &PairResult) -> Option<PathBuf> {
    (p.test.verdict == super::stats::Verdict::Differ).then(|| {
        let clean = |s: &str| s.replace(|c: char| !c.is_ascii_alphanumeric() && c != '-', "_");
        PathBuf::from(clean(&p.scene)).join(format!("differ-{}-vs-{}.png", clean(&p.a), clean(&p.b)))
    })
}

/// Writes the map of where a pair differs: the two images' mean luminance in grey, each block
/// tinted by its t-score, red where the first estimator is brighter, blue where darker; full
/// strength at the critical t and beyond, blocks that differ significantly outlined in white.
pub fn write_map(path: &Path, test: &PairTest, block: u32, images: (&Image, &Image)) -> Result<()> {
    let (a, b) = images;
    let (w, h) = (a.width, a.height);
    let grid_w = w.div_ceil(block);
    // Small images are drawn larger, each pixel a square of `zoom`.
    let zoom = MAP_WIDTH.div_ceil(w).max(1);
    let mut pixels = image::RgbImage::new(w * zoom, h * zoom);
    for yz in 0..h * zoom {
        for xz in 0..w * zoom {
            let (x, y) = (xz / zoom, yz / zoom);
            let i = (y * w + x) as usize;
            let lum = |p: [f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            let grey = 0.5 * lum_to_display(0.5 * (lum(a.mean[i]) + lum(b.mean[i])));
            let (bx, by) = (x / block, y / block);
            let t = &test.blocks[(by * grid_w + bx) as usize];
            let s = (t.t.abs() / test.t_critical).min(1.0) as f32;
            let tint = if t.t > 0.0 { [1.0, 0.1, 0.1] } else { [0.1, 0.3, 1.0] };
            let (bz, wz, hz) = (block * zoom, w * zoom, h * zoom);
            let edge = xz % bz == 0 || yz % bz == 0 || xz + 1 == wz || yz + 1 == hz;
            let rgb = match (t.rejected && edge, s > 0.0) {
                (true, _) => [1.0; 3],
                (false, true) => tint.map(|c| grey * (1.0 - s) + c * s),
                (false, false) => [grey; 3],
            };
            pixels.put_pixel(
                xz,
                yz,
                image::Rgb(rgb.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)),
            );
        }
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    pixels.save(path).with_context(|| format!("writing {}", path.display()))
}

/// The smallest width maps are drawn at (small images are enlarged by whole pixels).
const MAP_WIDTH: u32 = 256;

/// A luminance brought to [0, 1] for display (Reinhard, then the sRGB curve's gamma).
fn lum_to_display(l: f32) -> f32 {
    (l / (1.0 + l)).max(0.0).powf(1.0 / 2.2)
}

/// Where `verify` writes its HTML report in its output folder `out`.
pub fn html_path(out: &Path) -> PathBuf {
    out.join("report.html")
}

/// One scene's images for the HTML report: its folder and each estimator's label and image.
pub struct SceneImages {
    /// The scene's folder name (as the tables name the scene).
    pub scene: String,
    /// Each estimator's label and final image.
    pub images: Vec<(String, Image)>,
}

/// Writes the HTML report ([`html_path`]): the Markdown `md`, then per scene a viewer of the
/// estimators' images with the block t-map of every pair compared there (blocks of `block`
/// pixels).
pub fn write_html(out: &Path, md: &str, scenes: &[SceneImages], pairs: &[PairResult], block: u32) -> Result<()> {
    let mut report = crate::report::Report::new("lightgraph verify");
    report.markdown(md);
    for scene in scenes {
        report.viewer(&format!("scene {}", scene.scene));
        for (label, image) in &scene.images {
            report.image(label, image.width, image.height, &image.mean);
        }
        for p in pairs.iter().filter(|p| p.scene == scene.scene) {
            report.tmap(tmap(p, block));
        }
    }
    report.write(&html_path(out))
}

/// The t-map of a pair's blocks.
fn tmap(p: &PairResult, block: u32) -> crate::report::TMap {
    let across = p.grid_width.max(1);
    crate::report::TMap {
        a: p.a.clone(),
        b: p.b.clone(),
        block,
        grid: (across, p.test.blocks.len() as u32 / across),
        t: p.test.blocks.iter().map(|b| b.t).collect(),
        rejected: p.test.blocks.iter().map(|b| b.rejected).collect(),
        critical: p.test.t_critical,
    }
}
