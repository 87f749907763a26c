//! `lightgraph reference` and the error measures around it: a resumed reference equals one
//! rendered in one go, settings that would mix two estimates are refused, and `render
//! --reference` / `compare` check what they are given.

use crate::cli::{fails, lightgraph, temp_dir};
use lightgraph::film::Film;
use std::path::Path;

const SCENE: [&str; 6] = ["--scene", "cornell-diffuse", "--res", "16x12", "--spp", "2"];

/// Renders a reference of [`SCENE`] with `args` into `out`; returns it.
pub(crate) fn reference(args: &[&str], out: &Path) -> Film {
    let run = lightgraph(&[&["reference"], &SCENE[..], args, &["--out", out.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    Film::read(out).expect("a reference was written")
}

#[test]
fn a_resumed_reference_equals_one_rendered_at_once() {
    let dir = temp_dir("resume");
    let whole = reference(&["--frames", "6"], &dir.join("whole.exr"));
    let part = dir.join("part.exr");
    reference(&["--frames", "2"], &part);
    // Resuming takes the scene, resolution, spp and seed from the file; --frames is the
    // film's total, its 2 frames included.
    let run = lightgraph(&["reference", "--resume", part.to_str().unwrap(), "--frames", "6"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let resumed = Film::read(&part).unwrap();
    assert_eq!((resumed.frames, whole.frames), (6, 6));
    assert_eq!(resumed.samples_per_pixel(), 12);
    assert_eq!(resumed.info["seed"], "1000003");
    // The frames continue the random streams, so the six frames are the same ones; only the
    // f32 storage of the first part and the order of the f64 sums differ.
    let (a, b) = (whole.mean(), resumed.mean());
    let (va, vb) = (whole.variance_of_mean(), resumed.variance_of_mean());
    assert!(a.iter().flatten().any(|&v| v > 0.0), "the reference is black");
    for i in 0..a.len() {
        for c in 0..3 {
            assert!(
                (a[i][c] - b[i][c]).abs() <= 1e-5 * a[i][c].abs().max(1.0),
                "pixel {i}: {:?} vs {:?}",
                a[i],
                b[i]
            );
            assert!(
                (va[i][c] - vb[i][c]).abs() <= 1e-4 * va[i][c].abs().max(1e-3),
                "variance {i}: {:?} vs {:?}",
                va[i],
                vb[i]
            );
        }
    }
    assert!(dir.join("part.png").is_file());
}

#[test]
fn settings_that_would_mix_estimates_are_refused() {
    let dir = temp_dir("mix");
    let path = dir.join("ref.exr");
    reference(&["--frames", "1"], &path);
    let p = path.to_str().unwrap();
    let err = fails(&["reference", "--resume", p, "--frames", "2", "--seed", "5"]);
    assert!(
        err.contains("ref.exr") && err.contains("seed is '1000003' there, '5' here"),
        "{err}"
    );
    let err = fails(&["reference", "--resume", p, "--frames", "2", "--max-path-length", "3"]);
    assert!(err.contains("constants is '' there, 'MAX_PATH_LENGTH=3' here"), "{err}");
    let err = fails(&["reference", "--resume", p, "--frames", "2", "--first-frame", "0"]);
    assert!(
        err.contains("--first-frame 0 is inside the frames the film holds (up to 1)"),
        "{err}"
    );
    let err = fails(&["reference", "--resume", p, "--frames", "2", "--res", "8x8"]);
    // --frames is the film's total: a film that holds as many is refused before any work.
    let err_frames = fails(&["reference", "--resume", p, "--frames", "1"]);
    assert!(
        err_frames.contains("ref.exr: the film holds 1 frames already") && err_frames.contains("--frames 1"),
        "{err_frames}"
    );
    assert!(err.contains("the reference is 16x12, the render 8x8"), "{err}");
    // Runs with the reference's own seed would repeat its random numbers.
    let out = dir.join("cmp");
    let err = fails(&[
        "compare",
        "--runs",
        "pt",
        "--reference",
        p,
        "--seed",
        "1000003",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(err.contains("seed 1000003") && err.contains("another --seed"), "{err}");
    let err = fails(&[
        "compare",
        "--runs",
        "pt",
        "--reference",
        p,
        "--scene",
        "cornell-mitsuba",
    ]);
    assert!(
        err.contains("the reference shows scene 'cornell-diffuse', not 'cornell-mitsuba'"),
        "{err}"
    );
    let err = fails(&["compare", "--runs", "pt:NoSuchLayout", "--reference", p]);
    assert!(err.contains("NoSuchLayout"), "{err}");
    let err = fails(&[
        "compare",
        "--runs",
        "pt,pt:NaivePTmk",
        "--reference",
        p,
        "--baseline",
        "Nope",
    ]);
    assert!(
        err.contains("--baseline Nope is none of the runs (pt:NaivePTsk, pt:NaivePTmk)"),
        "{err}"
    );
    // A render writes a film with its settings: a reference can go on from it.
    let render = dir.join("render.exr");
    let run = lightgraph(
        &[
            &["render"],
            &SCENE[..],
            &["--frames", "1", "--out", render.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(run.status.success());
    let more = dir.join("more.exr");
    let run = lightgraph(&[
        "reference",
        "--resume",
        render.to_str().unwrap(),
        "--frames",
        "3",
        "--out",
        more.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let film = lightgraph::film::Film::read(&more).unwrap();
    assert_eq!((film.frames, film.ranges.clone()), (3, vec![(0, 3)]));
    // An EXR without lightgraph's settings is not a reference.
    let plain = dir.join("plain.exr");
    let image = lightgraph::run::Image {
        width: 16,
        height: 12,
        frames: 1,
        mean: vec![[1.0; 3]; 16 * 12],
        variance: vec![[0.0; 3]; 16 * 12],
    };
    lightgraph::output::write_exr(&plain, &image, &[]).unwrap();
    let err = fails(&[
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "16x12",
        "--frames",
        "1",
        "--reference",
        plain.to_str().unwrap(),
        "--out",
        dir.join("x.exr").to_str().unwrap(),
    ]);
    assert!(err.contains("plain.exr: not a lightgraph reference"), "{err}");
}

#[test]
fn render_reports_its_error_against_a_reference() {
    let dir = temp_dir("render-error");
    let path = dir.join("ref.exr");
    reference(&["--frames", "400"], &path);
    let render = |frames: &str| {
        let run = lightgraph(
            &[
                &["render"],
                &SCENE[..],
                &[
                    "--frames",
                    frames,
                    "--reference",
                    path.to_str().unwrap(),
                    "--out",
                    dir.join("r.exr").to_str().unwrap(),
                    "--force",
                ],
            ]
            .concat(),
        );
        let text = String::from_utf8_lossy(&run.stderr).to_string();
        assert!(run.status.success(), "{text}");
        let line = text
            .lines()
            .find(|l| l.starts_with("error against"))
            .unwrap_or_else(|| panic!("no error line:\n{text}"));
        let rmse: f64 = line
            .split("RMSE ")
            .nth(1)
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        rmse
    };
    // Four times the samples halve the expected RMSE (plus the reference's own noise): the
    // ratio of 1 to 16 frames is far from 1, whatever the noise of two small images.
    let (few, many) = (render("1"), render("16"));
    assert!(
        few.is_finite() && many.is_finite() && many < 0.75 * few,
        "RMSE {few} with 1 frame, {many} with 16"
    );
}

/// A reference of LVC-BPT records the average light sub-path length it measured (apart from
/// the constants: it weights the strategies, it does not change the image), resumes with that
/// value rather than a new measurement, and serves runs of other graphs in `compare`.
#[test]
fn a_measured_constant_is_recorded_resumed_and_left_out_of_compare() {
    let dir = temp_dir("measured");
    let path = dir.join("lvc.exr");
    let lvc = ["--graph", "bpt-lvc", "--frames", "1"];
    let film = reference(&lvc, &path);
    let measured = film.info.get("measured").cloned().unwrap_or_default();
    assert!(measured.starts_with("LVC_AVERAGE_LENGTH="), "measured: '{measured}'");
    assert_eq!(film.info["constants"], "");
    let p = path.to_str().unwrap();
    let run = lightgraph(&["reference", "--resume", p, "--frames", "2"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let resumed = Film::read(&path).unwrap();
    assert_eq!(
        (resumed.frames, resumed.info["measured"].as_str()),
        (2, measured.as_str())
    );
    // Another measurement is refused: it would mix two estimators.
    let err = fails(&[
        "reference",
        "--resume",
        p,
        "--frames",
        "3",
        "--set",
        "LVC_AVERAGE_LENGTH=9",
    ]);
    assert!(
        err.contains(&format!(
            "measured is '{measured}' there, 'LVC_AVERAGE_LENGTH=9.0' here"
        )),
        "{err}"
    );
    let out = dir.join("cmp");
    let run = lightgraph(&[
        "compare",
        "--runs",
        "pt",
        "--reference",
        p,
        "--time",
        "1s",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
}

/// `compare --gpus`: two runs on two devices of lavapipe at once, one each, both in the report;
/// an unknown adapter is refused naming it.
#[test]
fn compare_runs_on_two_devices() {
    let dir = temp_dir("compare-gpus");
    let path = dir.join("ref.exr");
    reference(&["--frames", "2"], &path);
    let p = path.to_str().unwrap();
    let out = dir.join("cmp");
    let o = out.to_str().unwrap();
    let runs = [
        "compare",
        "--runs",
        "pt:NaivePTsk,pt:NaivePTmk",
        "--reference",
        p,
        "--time",
        "1s",
    ];
    let run = lightgraph(&[&runs[..], &["--gpus", "0,0", "--out", o]].concat());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let curves = std::fs::read_to_string(out.join("curves.csv")).unwrap();
    assert!(
        curves.contains("pt:NaivePTsk") && curves.contains("pt:NaivePTmk"),
        "{curves}"
    );
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(summary.contains(" x2"), "{summary}");
    let err = fails(&[&runs[..], &["--gpus", "0,9", "--out", o]].concat());
    assert!(
        err.contains("GPU 1 ('9')") && err.contains("no adapter matches '9'"),
        "{err}"
    );
}
