//! `lightgraph study` end to end on tiny images: a comparison per scene and one summary, a
//! reference given (used as it is) or short (resumed), and names it cannot find refused
//! before anything renders.

use crate::cli::{fails, lightgraph, temp_dir};
use crate::reference::reference;
use lightgraph::reference::Reference;
use std::collections::BTreeMap;
use std::path::Path;

/// Tiny images and short layout measurements.
const TINY: [&str; 6] = ["--res", "16x12", "--layout-time", "30ms", "--per-decade", "3"];

/// Runs `lightgraph study` with `args` and [`TINY`].
fn study(args: &[&str]) {
    let run = lightgraph(&[&["study"], &TINY[..], args].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
}

/// The rows of a CSV file as maps from its header's column names.
fn csv(path: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    lines
        .map(|l| {
            let fields: Vec<&str> = l.split(',').collect();
            assert_eq!(fields.len(), header.len(), "{l}");
            header
                .iter()
                .map(|h| h.to_string())
                .zip(fields.iter().map(|f| f.to_string()))
                .collect()
        })
        .collect()
}

/// Borrowed arguments.
fn args(owned: &[String]) -> Vec<&str> {
    owned.iter().map(String::as_str).collect()
}

fn decodes(png: &Path) {
    image::open(png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
}

#[test]
fn a_study_writes_a_comparison_per_scene_and_one_summary() {
    let out = temp_dir("study").join("out");
    let o = out.to_str().unwrap();
    let scenes = ["cornell-diffuse", "cornell-glossy-point"];
    // One layout named, one graph whose layouts (PPMsk, PPMmk, PPMmkScreen) are measured.
    let estimators = ["pt:NaivePTsk", "ppm"];
    let joined = (scenes.join(","), estimators.join(","));
    study(&[
        "--scenes",
        &joined.0,
        "--estimators",
        &joined.1,
        "--time",
        // PPM's set-up takes most of a second on lavapipe; its curve needs a few samples more.
        "1500ms",
        // References of a few PT frames (the default reference graph, VCM, is not needed).
        "--reference-graph",
        "pt",
        "--reference-frames",
        "4",
        "--out",
        o,
    ]);
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    for name in scenes.iter().chain(&estimators) {
        assert!(md.contains(name), "summary.md does not name {name}:\n{md}");
    }
    // A study's runs render for their budget after their set-up (`--setup-on-clock` not given).
    assert!(md.contains("set-up off the clock"), "summary.md:\n{md}");
    let rows = csv(&out.join("summary.csv"));
    assert_eq!(rows.len(), scenes.len() * estimators.len());
    let layouts = csv(&out.join("layouts.csv"));
    for scene in scenes {
        let of_scene: Vec<_> = rows.iter().filter(|r| r["scene"] == scene).collect();
        let named: Vec<&str> = of_scene.iter().map(|r| r["estimator"].as_str()).collect();
        assert_eq!(named, estimators, "{scene}");
        // The winner is one of the estimators, and reached the best final error (the smallest
        // final RMSE) at a time no later than its budget.
        let winner = &of_scene[0]["winner"];
        let won = of_scene
            .iter()
            .find(|r| &r["estimator"] == winner)
            .expect("the winner is an estimator");
        let time: f64 = won["time_to_best_s"].parse().unwrap();
        assert!(time > 0.0 && time <= won["final_seconds"].parse::<f64>().unwrap() + 1e-6);
        let finals: Vec<f64> = of_scene.iter().map(|r| r["final_rmse"].parse().unwrap()).collect();
        let best: f64 = of_scene[0]["best_final_rmse"].parse().unwrap();
        assert_eq!(best, finals.iter().copied().fold(f64::INFINITY, f64::min), "{scene}");
        // PPM's layouts were each measured and the fastest chosen.
        let measured: Vec<_> = layouts.iter().filter(|r| r["scene"] == scene).collect();
        let names: Vec<&str> = measured.iter().map(|r| r["layout"].as_str()).collect();
        assert_eq!(names, ["PPMmk", "PPMmkScreen", "PPMsk"], "{scene}");
        let rate = |r: &BTreeMap<String, String>| r["samples_per_second"].parse::<f64>().unwrap();
        let fastest = measured.iter().max_by(|a, b| rate(a).total_cmp(&rate(b))).unwrap();
        assert_eq!(fastest["chosen"], "true", "{scene}: {measured:?}");
        assert_eq!(measured.iter().filter(|r| r["chosen"] == "true").count(), 1);
        let ppm = of_scene.iter().find(|r| r["estimator"] == "ppm").unwrap();
        assert_eq!(
            (ppm["layout"].as_str(), ppm["layout_chosen_by"].as_str()),
            (fastest["layout"].as_str(), "measurement")
        );
        check_comparison(
            &out.join(scene),
            &["pt:NaivePTsk".to_string(), format!("ppm:{}", fastest["layout"])],
        );
        let reference = Reference::read(&out.join("references").join(format!("{scene}.exr"))).unwrap();
        assert_eq!((reference.frames, reference.info["graph"].as_str()), (4, "pt"));
    }
}

/// A scene's comparison: curves with rows for every run in time order and finite errors,
/// the plot and each run's image.
fn check_comparison(dir: &Path, labels: &[String]) {
    let curves = csv(&dir.join("curves.csv"));
    for label in labels {
        let rows: Vec<_> = curves.iter().filter(|r| &r["run"] == label).collect();
        assert!(rows.len() >= 2, "{}: {label} has {} rows", dir.display(), rows.len());
        let times: Vec<f64> = rows.iter().map(|r| r["seconds"].parse().unwrap()).collect();
        assert!(times.windows(2).all(|w| w[0] < w[1]), "{label}: {times:?}");
        for r in &rows {
            let rmse: f64 = r["rmse"].parse().unwrap();
            assert!(rmse.is_finite() && rmse > 0.0, "{label}: {r:?}");
        }
        let stem = lightgraph::compare::file_stem(label);
        decodes(&dir.join(format!("{stem}.png")));
        assert!(dir.join(format!("{stem}.exr")).is_file());
    }
    decodes(&dir.join("rmse_vs_time.png"));
    assert!(dir.join("summary.md").is_file());
}

#[test]
fn a_study_uses_a_given_reference_and_resumes_a_short_one() {
    let dir = temp_dir("study-given");
    let refs = dir.join("refs");
    let path = refs.join("cornell-diffuse.exr");
    // cornell-diffuse at 16x12, 2 samples per pixel per frame.
    reference(&["--graph", "pt", "--frames", "4"], &path);
    let before = std::fs::read(&path).unwrap();
    let out = dir.join("out");
    let with = |frames: &str, graph: &str| -> Vec<String> {
        [
            "--scenes",
            "cornell-diffuse",
            "--estimators",
            "pt:NaivePTsk",
            "--references",
            refs.to_str().unwrap(),
            "--reference-frames",
            frames,
            "--reference-graph",
            graph,
            "--time",
            "150ms",
            "--out",
            out.to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec()
    };
    // The reference holds the 4 frames asked for: used as it is (a graph that does not exist
    // would fail any render).
    let given = with("4", "no-such-graph");
    study(&args(&given));
    assert_eq!(
        std::fs::read(&path).unwrap(),
        before,
        "the given reference was rewritten"
    );
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("(given)"), "{md}");
    // Asked for 6: resumed with its own graph.
    let resume = with("6", "pt");
    study(&args(&resume));
    let resumed = Reference::read(&path).unwrap();
    assert_eq!((resumed.frames, resumed.info["graph"].as_str()), (6, "pt"));
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("(resumed)") && md.contains("12 spp"), "{md}");
    // A reference of another size is refused, naming it, before anything renders.
    let err = fails(&[&["study", "--res", "8x8"], &args(&resume)[..]].concat());
    assert!(
        err.contains("cornell-diffuse.exr") && err.contains("the reference is 16x12"),
        "{err}"
    );
}

#[test]
fn a_study_names_what_it_cannot_find_before_rendering() {
    let out = temp_dir("study-bad").join("out");
    let o = out.to_str().unwrap();
    let run = |scenes: &str, estimators: &str| {
        let given = ["--scenes", scenes, "--estimators", estimators, "--out", o];
        fails(
            &[
                &["study"],
                &TINY[..],
                &given,
                &["--time", "1s", "--reference-graph", "pt"],
            ]
            .concat(),
        )
    };
    let err = run("cornell-diffuse,no-such-scene", "pt:NaivePTsk");
    assert!(err.contains("scene 'no-such-scene' not found"), "{err}");
    let err = run("cornell-diffuse", "pt:NoSuchLayout");
    assert!(err.contains("--estimators pt:NoSuchLayout"), "{err}");
    let err = run("cornell-diffuse", "pt,no-such-graph");
    assert!(err.contains("graph 'no-such-graph' not found"), "{err}");
    let err = run("cornell-diffuse,cornell-diffuse", "pt");
    assert!(err.contains("scene 'cornell-diffuse' is named twice"), "{err}");
    assert!(!out.exists(), "nothing was rendered or written");
    let err = fails(&["study", "--scene", "cornell-diffuse", "--scenes", "cornell-diffuse"]);
    assert!(err.contains("not --scene cornell-diffuse"), "{err}");
}
