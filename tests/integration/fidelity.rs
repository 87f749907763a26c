//! The fidelity suite (bench/peers/fidelity) against Mitsuba 3, without Mitsuba: each scene of
//! the suite has a reference in tests/data/fidelity, Mitsuba 3's own render at 64 x 64 (its mean
//! and the per-pixel variance of the mean from independent passes; `fidelity.py reference` made
//! them, their headers say with what). lightgraph's path tracer renders the scene on lavapipe at
//! 32 x 32 in batches, the reference is binned to 32 x 32, and the two images are compared as
//! `lightgraph verify` compares two estimators: Welch's t per 8 x 8 block and channel and of the
//! image mean, Holm-corrected to a family-wise error of 1% over the whole suite. A scene passes
//! when nothing differs and the test could have seen a difference of the mean of 2% (a scene
//! too noisy for that fails too: give it more frames). Scenes named `approx-*` are known
//! approximations, measured on the GPU (docs/mitsuba.md), not tested here.
//! Scenes named `media-*` hold participating media (Mitsuba's `volpath`; docs/media.md).

use crate::common::{data, render_batches};
use lightgraph::output::read_exr;
use lightgraph::run::LoadedScene;
use lightgraph::verify::stats::{Biased, BlockBatches, Estimates, TestSettings, Verdict, compare_estimates};
use lightgraph_scenes::bvh::BvhKind;
use std::path::{Path, PathBuf};

/// The rendered image's side, and the block's.
const SIZE: u32 = 32;
const BLOCK: u32 = 8;

/// Batches of frames (one sample per pixel a frame), and the frames of a batch: 32 batches
/// give the blocks' t 31 degrees of freedom (a critical |t| near 5.5 for the suite's ~1200
/// tests at 1%; with 8 it was 11).
const BATCHES: u32 = 32;
const FRAMES: u32 = 64;

/// Scenes whose image mean is noisier (small bright lights seen directly, delta lights'
/// indirect light) and the factor of frames they render, to see a 2% difference.
const NOISY: &[(&str, u32)] = &[("depth-1", 2), ("emitter-spheres", 4), ("lights-delta", 2)];

fn suite() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("bench/peers/fidelity/scenes")
}

/// The exact scenes of the suite, each with a reference (every `.xml` but the `approx-*` ones;
/// the participating media's `media-*` among them), by name.
fn exact_scenes() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(suite())
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            let name = path.file_stem()?.to_str()?.to_string();
            (path.extension()? == "xml" && !name.starts_with("approx-")).then_some(name)
        })
        .collect();
    names.sort();
    names
}

/// The reference of `name`, binned 2 x 2 to `SIZE` pixels: its estimates, and its passes.
fn reference(name: &str) -> (Estimates, usize) {
    let path = data(&format!("fidelity/{name}.exr"));
    let file = read_exr(&path).unwrap_or_else(|e| panic!("{name}: no reference ({e:#}): run fidelity.py reference"));
    let passes: usize = file.metadata["passes"].parse().unwrap();
    let (w, h) = file.size;
    assert_eq!((w, h), (2 * SIZE, 2 * SIZE), "{}", path.display());
    let channel = |c: &str| file.channel(c, &path).unwrap().to_vec();
    let (mean, variance) = (
        ["R", "G", "B"].map(channel),
        ["variance.R", "variance.G", "variance.B"].map(channel),
    );
    let binned = |planes: &[Vec<f32>; 3], scale: f64| -> Vec<[f64; 3]> {
        (0..SIZE * SIZE)
            .map(|i| {
                let (x, y) = (2 * (i % SIZE), 2 * (i / SIZE));
                [0, 1, 2].map(|c| {
                    let at = |dx: u32, dy: u32| planes[c][((y + dy) * w + x + dx) as usize] as f64;
                    (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) * scale
                })
            })
            .collect()
    };
    // The mean of four pixels, and the variance of that mean: their variances over 16.
    let estimates = Estimates::of_pixels(
        (SIZE, SIZE),
        BLOCK,
        &binned(&mean, 0.25),
        &binned(&variance, 1.0 / 16.0),
        (passes - 1) as f64,
    );
    (estimates, passes)
}

/// lightgraph's path tracer on `name`, in batches.
fn render(name: &str) -> BlockBatches {
    let path = suite().join(format!("{name}.xml"));
    let scene = LoadedScene::from_mitsuba(Path::new(&path), BvhKind::Bvh2).unwrap();
    let mut batches = BlockBatches::new((SIZE, SIZE), BLOCK);
    let factor = NOISY.iter().find(|n| n.0 == name).map_or(1, |n| n.1);
    for batch in render_batches(
        &scene,
        ("pt", "NaivePTsk"),
        (SIZE, SIZE),
        (BATCHES, factor * FRAMES),
        57,
        &[],
    ) {
        batches.add(&batch, 1);
    }
    batches
}

#[test]
fn every_exact_scene_of_the_suite_renders_as_mitsuba_3() {
    let scenes = exact_scenes();
    let references: Vec<String> = std::fs::read_dir(data("fidelity"))
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            (path.extension()? == "exr").then(|| path.file_stem().unwrap().to_str().unwrap().to_string())
        })
        .collect();
    let referenced = &scenes;
    let mut stale: Vec<&String> = references.iter().filter(|r| !referenced.contains(r)).collect();
    stale.sort();
    assert!(stale.is_empty(), "references of no exact scene of the suite: {stale:?}");
    assert!(scenes.len() >= 20, "the suite has {} exact scenes", scenes.len());
    let settings = TestSettings {
        alpha: 0.01,
        pairs: scenes.len(),
        detect_mean: 0.02,
        ..Default::default()
    };
    let mut failures = Vec::new();
    for name in &scenes {
        let (expected, passes) = reference(name);
        let test = compare_estimates(&render(name).estimates(), &expected, &settings, [&Biased::None; 2]);
        let (worst, block) = test.worst_block().map_or((0, 0.0), |(i, b)| (i, b.t));
        eprintln!(
            "{name}: mean {:+.3}% (t {:+.2}, detectable {:.2}%), {} of {} blocks differ (worst {worst}: t {block:+.2}, critical {:.2}); reference of {passes} passes: {}",
            100.0 * test.mean_difference,
            test.mean_t,
            100.0 * test.mean_detectable,
            test.blocks_rejected(),
            test.blocks.len(),
            test.t_critical,
            test.verdict.word(),
        );
        match test.verdict {
            Verdict::Differ => failures.push(format!("{name}: differs from Mitsuba 3")),
            _ if test.mean_detectable > settings.detect_mean => failures.push(format!(
                "{name}: too noisy to test (detectable {:.2}% of the mean): give it more frames",
                100.0 * test.mean_detectable
            )),
            _ => {}
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
