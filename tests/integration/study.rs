//! `lightgraph study` end to end on tiny images: a comparison per scene and one summary, a
//! reference given (used as it is) or short (resumed), names it cannot find refused before
//! anything renders, a study interrupted and resumed; and a run's clock, which starts after
//! the first frame's compilation.

use crate::cli::{fails, lightgraph, temp_dir};
use crate::common::gpu;
use crate::reference::reference;
use lightgraph::compare::{RunBudget, run};
use lightgraph::film::Film;
use lightgraph::run::{Run, RunSpec, load_graph, load_scene};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

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
        // The winner (or the first of a tie, `tie: a; b`) is one of the estimators, ended with
        // the best final error (the smallest final RMSE) and reached it at a time no later
        // than its budget.
        let winner = &of_scene[0]["winner"];
        let first = winner
            .strip_prefix("tie: ")
            .map_or(winner.as_str(), |t| t.split("; ").next().unwrap());
        let won = of_scene
            .iter()
            .find(|r| r["estimator"] == first)
            .unwrap_or_else(|| panic!("the winner '{winner}' is an estimator"));
        let time: f64 = won["time_to_best_s"].parse().unwrap();
        assert!(time > 0.0 && time <= won["final_seconds"].parse::<f64>().unwrap() + 1e-6);
        let finals: Vec<f64> = of_scene.iter().map(|r| r["final_rmse"].parse().unwrap()).collect();
        let best: f64 = of_scene[0]["best_final_rmse"].parse().unwrap();
        assert_eq!(best, finals.iter().copied().fold(f64::INFINITY, f64::min), "{scene}");
        assert_eq!(won["final_rmse"].parse::<f64>().unwrap(), best, "{scene}");
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
        let reference = Film::read(&out.join("references").join(format!("{scene}.exr"))).unwrap();
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
    // Asked for 6: resumed with its own graph (the study's folder, of the run before,
    // replaced with --force).
    let mut resume = with("6", "pt");
    resume.push("--force".into());
    study(&args(&resume));
    let resumed = Film::read(&path).unwrap();
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

/// Waits until `path` exists, at most `seconds`.
fn wait_for(path: &Path, seconds: u64) -> bool {
    let start = Instant::now();
    while !path.exists() {
        if start.elapsed() > Duration::from_secs(seconds) {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    true
}

/// The rows of a comparison's `curves.csv` of each run, by label.
fn rows_per_run(dir: &Path) -> BTreeMap<String, usize> {
    let mut runs = BTreeMap::new();
    for row in csv(&dir.join("curves.csv")) {
        *runs.entry(row["run"].clone()).or_insert(0) += 1;
    }
    runs
}

#[test]
fn an_interrupted_study_keeps_its_finished_runs_and_resumes_to_the_whole_table() {
    let dir = temp_dir("study-interrupted");
    let out = dir.join("out");
    let given: Vec<String> = [
        "--scenes",
        "cornell-diffuse",
        "--estimators",
        "pt:NaivePTsk,pt:RegenerationPTsk",
        "--time",
        "2s",
        "--reference-graph",
        "pt",
        "--reference-frames",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec();
    let child = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args([&["study"], &TINY[..], &args(&given)].concat())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    // The first run's image is written when it ends: the second is then in flight.
    let scene = out.join("cornell-diffuse");
    let first = scene.join("pt-NaivePTsk.exr");
    let appeared = wait_for(&first, 120);
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let ended = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&ended.stderr);
    assert!(appeared && kill.unwrap().success(), "{stderr}");
    assert_eq!(ended.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted by SIGINT"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The command printed to go on: the study's own with --resume.
    let start = stderr.find("`lightgraph study ").expect("the command that goes on") + 1;
    let printed = &stderr[start..start + stderr[start..].find('`').expect("a closing backquote")];
    assert!(printed.ends_with(" --resume"), "{printed}");
    // The finished run is kept, the dropped one left no rows.
    let kept = rows_per_run(&scene);
    assert_eq!(kept.keys().collect::<Vec<_>>(), ["pt:NaivePTsk"], "{stderr}");
    let md = std::fs::read_to_string(scene.join("summary.md")).unwrap();
    assert!(md.contains("**1 of 2 runs done so far.**"), "{md}");
    let image = std::fs::read(&first).unwrap();
    // Other settings are refused, naming the one that differs.
    let mut other = given.clone();
    other[5] = "3s".into();
    let err = fails(&[&["study", "--resume"], &TINY[..], &args(&other)].concat());
    assert!(err.contains("budget '2s") && err.contains("budget '3s"), "{err}");
    let resumed = lightgraph(&printed.split_whitespace().skip(1).collect::<Vec<_>>());
    assert!(
        resumed.status.success(),
        "{printed}: {}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let all = rows_per_run(&scene);
    assert_eq!(all.keys().collect::<Vec<_>>(), ["pt:NaivePTsk", "pt:RegenerationPTsk"]);
    assert_eq!(
        all["pt:NaivePTsk"], kept["pt:NaivePTsk"],
        "the finished run was not rendered again"
    );
    assert_eq!(std::fs::read(&first).unwrap(), image);
    let rows = csv(&out.join("summary.csv"));
    assert_eq!(rows.len(), 2);
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(!md.contains("done so far"), "{md}");
}

#[test]
fn a_runs_first_error_sample_is_a_frames_render_not_its_compile() {
    // LVC-BPT's pipelines take most of a second to compile on lavapipe, at their first
    // dispatch; a 16x16 frame takes milliseconds.
    let scene = Arc::new(load_scene("cornell-glossy-sun").unwrap());
    let graph = load_graph("bpt-lvc").unwrap();
    let decl = graph.layout("LVC-BPTsk").unwrap().clone();
    let mut job = Run::with_scene(&RunSpec::default(), graph, ("LVC-BPTsk".into(), decl), scene).unwrap();
    job.options = crate::common::options((16, 16), 1, 7, &[], Default::default());
    let budget = RunBudget {
        time: Duration::from_secs(1),
        setup_on_clock: false,
    };
    let black = vec![[0.0f32; 3]; 256];
    let result = run(gpu(), &job, "bpt-lvc".to_string(), budget, &black, 6, |_, _, _| {}).unwrap();
    let curve = &result.curve;
    let (first, last) = (&curve.samples[0], curve.last());
    // The warm-up frame is in neither the counts nor the image.
    assert_eq!((first.frames, first.samples_per_pixel), (1, 1));
    assert_eq!(result.image.frames, last.frames);
    let per_frame = (last.seconds - first.seconds) / (last.frames - first.frames) as f64;
    // A compile in the first sample would make it about as long as the set-up, which holds
    // the compile; a frame is a fraction of it. Only against the set-up, which a loaded
    // machine slows alike: against the later frames, one stalled frame under CI's load
    // (0.136 s against 5 ms frames) failed a bound of ten frames and 50 ms.
    assert!(
        first.seconds < 0.5 * curve.setup_seconds,
        "first sample at {:.4} s, later frames {per_frame:.4} s each, set-up {:.3} s",
        first.seconds,
        curve.setup_seconds
    );
}
