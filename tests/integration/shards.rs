//! Sample-split rendering: shards of one run, disjoint frame ranges of the same random
//! streams (`Session::first_frame`, `--first-frame`), merged as films equal the run itself to
//! float rounding, for path tracing, LVC-BPT and photon mapping (whose radius shrinks with the
//! global frame index); the CLI's `render --first-frame` and `merge` end to end; and one run
//! on several GPUs (`render --gpus`, here two devices of lavapipe) equals it on one.

use crate::cli::{fails, lightgraph, temp_dir};
use crate::common::{borrowed, gpu, measured, options};
use lightgraph::film::Film;
use lightgraph::run::{LoadedScene, Session, load_graph, load_scene};
use lightgraph_engine::ConstValue;
use std::collections::BTreeMap;

const SIZE: u32 = 16;

/// The largest relative difference float rounding gives between two renders of the same frames
/// by an estimator that splats light sub-paths with atomic float adds (see
/// `shards_merged_equal_one_run`).
const SPLAT_ROUNDING: f64 = 2e-4;
const SEED: u32 = 5;

/// Frames `first .. first + frames` of `graph` in `layout` on `scene`, as a film.
fn film_of(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    (first, frames): (u32, u32),
    constants: &[(&str, ConstValue)],
) -> Film {
    let graph = load_graph(graph).unwrap();
    let opts = options((SIZE, SIZE), 2, SEED, constants, Default::default());
    let mut session = Session::new(gpu(), &graph, layout, scene, opts).unwrap();
    session.first_frame = first;
    session.render_frames(frames).unwrap();
    let mut film = Film::new((SIZE, SIZE), BTreeMap::new());
    film.absorb(&session.accumulation().unwrap()).unwrap();
    film
}

/// The largest difference of two films' means relative to the larger (floored at 1e-3).
pub(crate) fn largest_difference(a: &Film, b: &Film) -> f64 {
    let mut worst = 0f64;
    for (p, q) in a.mean().iter().zip(&b.mean()) {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
        }
    }
    worst
}

#[test]
fn shards_merged_equal_one_run() {
    // Six frames in one session against shards of 2 and 4 frames (unequal on purpose). The
    // GPU sums each run in f32 (with compensation), so the means agree to float rounding:
    // 1e-5 relative is far below the noise of a 6-frame render (percents) and far above
    // rounding, except where light sub-paths splat into pixels with atomic float adds in
    // whatever order the threads run (LVC-BPT): many adds a pixel, each rounding to 6e-8,
    // measured up to 4.6e-5 on a dim pixel, so SPLAT_ROUNDING there. LVC-BPT's measured
    // average sub-path length is measured once and given to every shard (as the CLI's films
    // record it): on lavapipe the measuring frame's count can differ between sessions
    // (docs/testing.md), and other values weight the strategies differently. A shard that repeated the
    // first frames, or a radius that restarted with each shard, would differ by the noise
    // (over 1e-3, checked below).
    let pm = [("PM_RADIUS", ConstValue::F32(0.05))];
    type Run<'a> = (&'a str, &'a str, &'a str, &'a [(&'a str, ConstValue)]);
    let runs: [Run; 3] = [
        ("pt", "NaivePTsk", "cornell-diffuse", &[]),
        ("bpt-lvc", "LVC-BPTsk", "cornell-glossy-point", &[]),
        ("ppm", "PPMsk", "cornell-glossy-mirrorball", &pm),
    ];
    for (graph, layout, scene_name, constants) in runs {
        let scene = load_scene(scene_name).unwrap();
        let mut owned: Vec<(String, ConstValue)> = constants.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        owned.extend(measured(&scene, graph, layout, ((SIZE, SIZE), 2, SEED), constants));
        let constants = &borrowed(&owned)[..];
        let whole = film_of(&scene, graph, layout, (0, 6), constants);
        let mut merged = film_of(&scene, graph, layout, (0, 2), constants);
        merged
            .merge(&film_of(&scene, graph, layout, (2, 4), constants), "b.exr".as_ref())
            .unwrap();
        assert_eq!((merged.frames, merged.ranges.clone()), (6, vec![(0, 6)]));
        let worst = largest_difference(&merged, &whole);
        let tolerance = if graph == "bpt-lvc" { SPLAT_ROUNDING } else { 1e-5 };
        assert!(
            worst < tolerance,
            "{graph}: the merged shards differ from one run by {worst:.2e}"
        );
        let other_frames = film_of(&scene, graph, layout, (6, 6), constants);
        assert!(
            largest_difference(&other_frames, &whole) > 1e-3,
            "{graph}: other frames give the same image; the test has no power"
        );
    }
}

#[test]
fn render_shards_merge_through_the_cli() {
    let dir = temp_dir("shards");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let render = |seed: &str, first: &str, frames: &str, out: &str| {
        let args = [
            "render",
            "--scene",
            "cornell-diffuse",
            "--res",
            "12x8",
            "--seed",
            seed,
            "--frames",
            frames,
            "--first-frame",
            first,
            "--out",
            out,
        ];
        let run = lightgraph(&args);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    };
    render("3", "0", "3", &path("whole.exr"));
    render("3", "0", "1", &path("a.exr"));
    render("3", "1", "2", &path("b.exr"));
    let run = lightgraph(&["merge", &path("a.exr"), &path("b.exr"), "--out", &path("m.exr")]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(dir.join("m.png").is_file());
    let merged = Film::read(&dir.join("m.exr")).unwrap();
    let whole = Film::read(&dir.join("whole.exr")).unwrap();
    assert_eq!((merged.frames, merged.ranges.clone()), (3, vec![(0, 3)]));
    let worst = largest_difference(&merged, &whole);
    assert!(worst < 1e-5, "merged shards differ from one run by {worst:.2e}");
    // The same frames twice, and a film of another seed, are refused.
    let err = fails(&["merge", &path("a.exr"), &path("whole.exr"), "--out", &path("x.exr")]);
    assert!(
        err.contains("whole.exr") && err.contains("frames 0..3 overlap frames 0..1"),
        "{err}"
    );
    render("4", "3", "1", &path("seed4.exr"));
    let err = fails(&["merge", &path("whole.exr"), &path("seed4.exr"), "--out", &path("x.exr")]);
    assert!(
        err.contains("seed4.exr") && err.contains("seed is '4' there, '3' here"),
        "{err}"
    );
}

#[test]
fn a_run_on_two_devices_equals_it_on_one() {
    let dir = temp_dir("gpus");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let base = [
        "render",
        "--scene",
        "cornell-glossy-point",
        "--graph",
        "bpt-lvc",
        "--res",
        "16x12",
        "--frames",
        "8",
    ];
    let one = lightgraph(&[&base[..], &["--out", &path("one.exr")]].concat());
    assert!(one.status.success(), "{}", String::from_utf8_lossy(&one.stderr));
    // The film records the measured average sub-path length; the run on two devices is given
    // it (as shards are), so both render one estimator.
    let recorded = Film::read(&dir.join("one.exr")).unwrap().info.get("measured").cloned();
    let measured = recorded
        .clone()
        .filter(|m| m.starts_with("LVC_AVERAGE_LENGTH="))
        .unwrap_or_else(|| panic!("the film does not record the measured constant: {recorded:?}"));
    let set = ["--set", measured.as_str()];
    let two = lightgraph(&[&base[..], &set, &["--gpus", "0,0", "--out", &path("two.exr")]].concat());
    let stderr = String::from_utf8_lossy(&two.stderr);
    assert!(two.status.success(), "{stderr}");
    assert!(
        stderr.contains("on 2 GPUs") && stderr.contains("GPU 0 (") && stderr.contains("GPU 1 ("),
        "{stderr}"
    );
    let (one, two) = (
        Film::read(&dir.join("one.exr")).unwrap(),
        Film::read(&dir.join("two.exr")).unwrap(),
    );
    assert_eq!((two.frames, two.ranges.clone()), (8, vec![(0, 8)]));
    assert_eq!(one.info.get("measured"), two.info.get("measured"));
    let worst = largest_difference(&one, &two);
    assert!(worst < SPLAT_ROUNDING, "two devices differ from one by {worst:.2e}");
    // A reference too.
    let reference = |extra: &[&str], out: &str| {
        let args = [
            &[
                "reference",
                "--scene",
                "cornell-diffuse",
                "--res",
                "12x8",
                "--frames",
                "5",
            ][..],
            extra,
            &["--out", out],
        ];
        let run = lightgraph(&args.concat());
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        Film::read(out.as_ref()).unwrap()
    };
    let (one, two) = (
        reference(&[], &path("ref1.exr")),
        reference(&["--gpus", "0,0"], &path("ref2.exr")),
    );
    assert_eq!((two.frames, two.ranges.clone()), (5, vec![(0, 5)]));
    let worst = largest_difference(&one, &two);
    assert!(
        worst < 1e-5,
        "a reference on two devices differs from one by {worst:.2e}"
    );
    let err = fails(&[&base[..], &["--gpus", "0,9", "--out", &path("x.exr")]].concat());
    assert!(
        err.contains("GPU 1 ('9')") && err.contains("no adapter matches '9'"),
        "{err}"
    );
    let err = fails(&[&base[..], &["--gpus", "5", "--out", &path("x.exr")]].concat());
    assert!(err.contains("--gpus 5: this machine has"), "{err}");
}
