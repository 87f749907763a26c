//! Every option checked before any work: zero and negative counts, times and sizes, images
//! too large for the engine's counts or the host's memory, unknown constants and values of
//! the wrong type are refused with a one-line error naming the option, and nothing is written.

use crate::cli::{fails, lightgraph, temp_dir};

/// Runs with an option clap's value parsers refuse: exit code 2 (a usage error), an
/// `error:` line, no panic; returns stderr.
pub(crate) fn usage_error(args: &[&str]) -> String {
    let out = lightgraph(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{args:?} should be a usage error: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    stderr
}

/// Runs `command` with `args` and `--out` in a fresh folder (`file` there, or the folder
/// itself when None), which must fail (a usage error, exit 2, when a needle quotes an option
/// as clap does) with an error line holding every one of `needles` and leave nothing at
/// `--out`; returns that line.
fn refused(name: &str, command: &str, args: &[&str], file: Option<&str>, needles: &[&str]) -> String {
    let usage = needles.iter().any(|n| n.starts_with("'--"));
    let dir = temp_dir(&format!("options-{name}"));
    let out = match file {
        Some(f) => dir.join(f),
        None => dir.join("out"),
    };
    let mut argv = vec![command];
    argv.extend_from_slice(args);
    let out_text = out.to_str().unwrap().to_string();
    argv.extend_from_slice(&["--out", &out_text]);
    let stderr = if usage { usage_error(&argv) } else { fails(&argv) };
    let line = stderr.lines().find(|l| l.starts_with("error:")).expect("an error line");
    for needle in needles {
        assert!(
            line.contains(needle),
            "{argv:?}: '{needle}' not in the error line: {stderr}"
        );
    }
    assert!(!out.exists(), "{argv:?} wrote {}", out.display());
    assert!(!out.with_extension("png").exists(), "{argv:?} wrote a PNG");
    line.to_string()
}

/// [`refused`] for `lightgraph render`, whose `--out` is a file.
fn render_refused(name: &str, args: &[&str], needles: &[&str]) -> String {
    refused(name, "render", args, Some("x.exr"), needles)
}

#[test]
fn render_refuses_zero_and_negative_counts_and_times() {
    let cases: [(&[&str], &str); 11] = [
        (&["--frames", "0"], "'--frames <FRAMES>'"),
        (&["--frames", "-1"], "'--frames <FRAMES>'"),
        (&["--time", "0s"], "'--time <TIME>'"),
        (&["--time", "-1s"], "'--time <TIME>'"),
        (&["--tune-time", "0s"], "'--tune-time <TUNE_TIME>'"),
        (&["--spp", "0"], "'--spp <SPP>'"),
        (&["--res", "0x4"], "'--res <RES>'"),
        (&["--res", "-4x4"], "'--res <RES>'"),
        (&["--max-path-length", "0"], "'--max-path-length <MAX_PATH_LENGTH>'"),
        (&["--workgroup", "0"], "'--workgroup <WORKGROUP>'"),
        (&["--threads", "-3"], "'--threads <THREADS>'"),
    ];
    for (i, (args, option)) in cases.iter().enumerate() {
        let why = if args[1].ends_with('s') { "zero" } else { "at least 1" };
        render_refused(&format!("render-{i}"), args, &[option, why]);
    }
}

#[test]
fn every_command_refuses_zero_counts_and_times() {
    let cases: [(&str, &[&str], &str); 14] = [
        ("reference", &["--frames", "0"], "'--frames <FRAMES>'"),
        ("reference", &["--time", "0s"], "'--time <TIME>'"),
        (
            "reference",
            &["--frames", "2", "--checkpoint", "0s"],
            "'--checkpoint <CHECKPOINT>'",
        ),
        (
            "compare",
            &["--reference", "r.exr", "--runs", "pt", "--time", "0s"],
            "'--time <TIME>'",
        ),
        (
            "compare",
            &["--reference", "r.exr", "--runs", "pt", "--per-decade", "0"],
            "'--per-decade",
        ),
        (
            "study",
            &["--scenes", "cornell-diffuse", "--time", "0s"],
            "'--time <TIME>'",
        ),
        (
            "study",
            &["--scenes", "cornell-diffuse", "--layout-time", "-2s"],
            "'--layout-time",
        ),
        (
            "study",
            &["--scenes", "cornell-diffuse", "--reference-spp", "0"],
            "'--reference-spp",
        ),
        ("bench", &["--time", "0s"], "'--time <TIME>'"),
        ("bench", &["--points", "640x0x1"], "'--points <POINTS>'"),
        ("verify", &["--time", "0s"], "'--time <TIME>'"),
        ("verify", &["--frames", "0"], "'--frames <FRAMES>'"),
        ("stress", &["--frames", "0"], "'--frames <FRAMES>'"),
        ("stress", &["--scale", "0"], "'--scale <SCALE>'"),
    ];
    for (i, (command, args, option)) in cases.iter().enumerate() {
        let file = (*command == "reference").then_some("r.exr");
        refused(&format!("every-{i}"), command, args, file, &[option]);
    }
}

/// [`render_refused`] for each case: a name, the arguments and the words of the error.
fn renders_refused(cases: &[(&str, &[&str], &[&str])]) {
    for (name, args, needles) in cases {
        render_refused(name, args, needles);
    }
}

#[test]
fn an_unknown_constant_names_the_graph_and_the_close_names() {
    renders_refused(&[
        // The name is the problem, whatever the value.
        (
            "unknown-u32",
            &["--set", "NO_SUCH=1"],
            &["--set NO_SUCH=1", "graph pt has no constant NO_SUCH"],
        ),
        (
            "unknown-f32",
            &["--set", "NO_SUCH=0.5"],
            &["--set NO_SUCH=0.5", "graph pt has no constant NO_SUCH"],
        ),
        // A constant of another graph: pt has none of photon mapping's, and lists its own.
        (
            "other-graph",
            &["--graph", "pt", "--set", "PM_RADIUS=0.5"],
            &["graph pt has no constant PM_RADIUS", "MAX_PATH_LENGTH"],
        ),
        (
            "typo",
            &["--graph", "ppm", "--set", "PM_RADUIS=0.5"],
            &["graph ppm has no constant PM_RADUIS", "close names: PM_RADIUS"],
        ),
        (
            "host",
            &["--set", "PATHS=4"],
            &["--set PATHS=4", "image size", "cannot be set"],
        ),
    ]);
    refused(
        "study-run",
        "study",
        &["--scenes", "cornell-diffuse", "--estimators", "pt@PM_RADIUS=0.5"],
        None,
        &["--estimators @PM_RADIUS=0.5", "graph pt has no constant PM_RADIUS"],
    );
}

#[test]
fn a_value_of_the_wrong_type_names_the_constant_its_type_and_the_value() {
    renders_refused(&[
        (
            "u32",
            &["--set", "MAX_PATH_LENGTH=abc"],
            &["--set MAX_PATH_LENGTH=abc", "is a u32", "'abc'"],
        ),
        (
            "bool",
            &["--graph", "vcm", "--set", "VCM_MERGE=2"],
            &["VCM_MERGE is a bool", "'2'"],
        ),
        (
            "f32",
            &["--graph", "ppm", "--set", "PM_RADIUS=inf"],
            &["PM_RADIUS is an f32", "'inf'"],
        ),
    ]);
}

#[test]
fn an_image_the_engine_cannot_count_is_refused_before_allocating() {
    let limit = u32::MAX.to_string();
    renders_refused(&[
        (
            "paths",
            &["--res", "100000x100000", "--frames", "1"],
            &["--res 100000x100000 with --spp 1", "10000000000 paths", &limit],
        ),
        (
            "spp",
            &["--res", "256x256", "--spp", "100000", "--frames", "1"],
            &["--spp 100000", "6553600000 paths", &limit],
        ),
    ]);
    refused(
        "bench",
        "bench",
        &["--points", "100000x100000x1"],
        None,
        &["'--points <POINTS>'", "10000000000 paths"],
    );
}

#[test]
fn a_film_larger_than_the_host_memory_is_refused_before_allocating() {
    // 65535 x 65535 pixels fit the 32-bit counts; their film (128 bytes a pixel, 512 GiB)
    // does not fit the memory of the machines this runs on, and where it did, the GPU's
    // buffers could not hold its sums: either way a one-line error before any allocation.
    let line = render_refused("memory", &["--res", "65535x65535", "--frames", "1"], &["65535x65535"]);
    assert!(
        line.contains("GiB of host memory") || line.contains("adapter"),
        "{line}"
    );
}

/// A budget of time and one of frames together are refused, by every command that takes
/// both (a render given both used to ignore --frames without a word).
#[test]
fn a_time_and_a_number_of_frames_together_are_refused() {
    for (command, args) in [
        ("render", &["--time", "1s", "--frames", "5"][..]),
        ("reference", &["--time", "1s", "--frames", "5"]),
        ("verify", &["--time", "1s", "--frames", "5"]),
        (
            "study",
            &[
                "--scenes",
                "cornell-diffuse",
                "--reference-time",
                "1s",
                "--reference-frames",
                "5",
            ],
        ),
    ] {
        let dir = temp_dir(&format!("time-and-frames-{command}"));
        let out = dir.join(if matches!(command, "render" | "reference") {
            "x.exr"
        } else {
            "out"
        });
        let mut argv = vec![command];
        argv.extend_from_slice(args);
        argv.extend_from_slice(&["--res", "8x8", "--out", out.to_str().unwrap()]);
        let err = usage_error(&argv);
        assert!(
            err.contains("cannot be used with") && err.contains("frames"),
            "{argv:?}: {err}"
        );
        assert!(!out.exists(), "{argv:?} wrote {}", out.display());
    }
}
