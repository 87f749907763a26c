//! Nothing lost: a render or reference stopped by SIGINT or SIGTERM writes its film and exits
//! with the signal's status; `--resume` goes on from the film to the image an uninterrupted
//! run gives; outputs never overwrite a film unless asked.

use crate::cli::{fails, lightgraph, temp_dir};
use crate::shards::largest_difference;
use lightgraph::film::Film;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Frames of the interrupted runs: more than a loaded lavapipe renders at 16×16 before the
/// signal (sent once the first checkpoint is on disk), few enough for a short test.
const FRAMES: &str = "1200";

/// Starts `lightgraph ARGS` in the background.
fn start(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        // No test takes a layout from a cache of the machine's own (tests/integration/layout_cache.rs).
        .env(
            "LIGHTGRAPH_CACHE",
            std::env::temp_dir().join(format!("lightgraph-cache-{}", std::process::id())),
        )
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts")
}

/// Waits until `file` exists (the run's first checkpoint: frames are rendered), then sends
/// `signal` (INT or TERM) and returns the exit code and stderr.
fn interrupt_once_written(mut child: Child, file: &Path, signal: &str) -> (Option<i32>, String) {
    let started = Instant::now();
    while !file.exists() {
        if let Ok(Some(status)) = child.try_wait() {
            let out = child.wait_with_output().unwrap();
            panic!(
                "the run ended ({status}) before its first checkpoint: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        assert!(started.elapsed() < Duration::from_secs(300), "no checkpoint in 300 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let out = child.wait_with_output().unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).to_string())
}

/// The render of the diffuse box at 16×16 these tests make, with `extra` arguments.
fn box_render<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", "--scene", "cornell-diffuse", "--res", "16x16", "--seed", "7"];
    args.extend_from_slice(extra);
    args
}

/// The reference of the diffuse box at 16×16 these tests make, with `extra` arguments.
fn box_reference<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["reference", "--scene", "cornell-diffuse", "--res", "16x16"];
    args.extend_from_slice(extra);
    args
}

/// Renders the diffuse box at 16×16 with `extra` arguments; panics on failure.
fn render(extra: &[&str]) {
    let run = lightgraph(&box_render(extra));
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
}

#[test]
fn sigint_keeps_the_frames_and_resume_equals_an_uninterrupted_run() {
    let dir = temp_dir("sigint");
    let (cut, whole) = (dir.join("cut.exr"), dir.join("whole.exr"));
    let (cut_s, whole_s) = (cut.to_str().unwrap(), whole.to_str().unwrap());
    let args = box_render(&["--frames", FRAMES, "--checkpoint", "100ms", "--out", cut_s]);
    let (code, stderr) = interrupt_once_written(start(&args), &cut, "INT");
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("SIGINT") && stderr.contains("--resume"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let kept = Film::read(&cut).unwrap();
    let total: u64 = FRAMES.parse().unwrap();
    assert!(
        kept.frames > 0 && kept.frames < total,
        "the interrupted film holds {} of {total} frames",
        kept.frames
    );
    assert!(dir.join("cut.png").is_file());
    // Resumed with the run's total: the frames it lacked, then the whole run's image.
    render(&["--frames", FRAMES, "--resume", cut_s]);
    render(&["--frames", FRAMES, "--out", whole_s]);
    let (resumed, whole) = (Film::read(&cut).unwrap(), Film::read(&whole).unwrap());
    assert_eq!(resumed.ranges, vec![(0, total)]);
    // The same frames summed in two parts instead of one: float rounding only (see
    // shards::shards_merged_equal_one_run for the bound).
    let worst = largest_difference(&resumed, &whole);
    assert!(worst < 1e-5, "resumed differs from uninterrupted by {worst:.2e}");
}

#[test]
fn sigterm_keeps_the_frames_of_a_render_on_gpus_and_of_a_reference() {
    let dir = temp_dir("sigterm");
    let (gpus, reference) = (dir.join("gpus.exr"), dir.join("reference.exr"));
    let (gpus_s, reference_s) = (gpus.to_str().unwrap(), reference.to_str().unwrap());
    let args = box_render(&[
        "--frames",
        FRAMES,
        "--gpus",
        "1",
        "--checkpoint",
        "100ms",
        "--out",
        gpus_s,
    ]);
    let (code, stderr) = interrupt_once_written(start(&args), &gpus, "TERM");
    assert_eq!(code, Some(143), "{stderr}");
    let kept = Film::read(&gpus).unwrap();
    assert!(kept.frames > 0 && kept.ranges.len() == 1, "{:?}", kept.ranges);
    render(&["--frames", FRAMES, "--gpus", "1", "--resume", gpus_s]);
    assert_eq!(Film::read(&gpus).unwrap().ranges, vec![(0, FRAMES.parse().unwrap())]);
    let total = "1000000";
    let args = box_reference(&["--frames", total, "--checkpoint", "100ms", "--out", reference_s]);
    let (code, stderr) = interrupt_once_written(start(&args), &reference, "TERM");
    assert_eq!(code, Some(143), "{stderr}");
    assert!(
        stderr.contains("SIGTERM") && stderr.contains("reference --resume"),
        "{stderr}"
    );
    // The command printed to go on asks for the run's frames in all, as --frames counts
    // them with --resume (it printed the frames left).
    let printed = printed_resume_command(&stderr);
    assert!(printed.windows(2).any(|w| w == ["--frames", total]), "{printed:?}");
    let kept = Film::read(&reference).unwrap();
    assert!(kept.frames > 0 && kept.frames < 1_000_000, "{}", kept.frames);
    // --frames is the film's total: two more than it holds renders two frames.
    let two_more = (kept.frames + 2).to_string();
    let run = lightgraph(&["reference", "--resume", reference_s, "--frames", &two_more]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert_eq!(Film::read(&reference).unwrap().frames, kept.frames + 2);
}

#[test]
fn outputs_never_overwrite_a_film_unless_asked() {
    let dir = temp_dir("outputs");
    let film = dir.join("film.exr");
    let film_s = film.to_str().unwrap();
    // A .png --out would have been overwritten by its own preview: refused.
    let png = dir.join("film.png");
    let err = fails(&[
        "render",
        "--res",
        "8x8",
        "--frames",
        "1",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(err.contains("--out") && err.contains(".exr"), "{err}");
    assert!(!png.exists());
    render(&["--frames", "2", "--out", film_s]);
    let written = std::fs::metadata(&film).unwrap().modified().unwrap();
    let err = fails(&box_render(&["--frames", "2", "--out", film_s]));
    assert!(
        err.contains("exists") && err.contains("--force") && err.contains("--resume"),
        "{err}"
    );
    assert_eq!(std::fs::metadata(&film).unwrap().modified().unwrap(), written);
    render(&["--frames", "3", "--out", film_s, "--force"]);
    assert_eq!(Film::read(&film).unwrap().frames, 3);
    let written = std::fs::metadata(&film).unwrap().modified().unwrap();
    // A resumed film's settings are checked as merge checks them, and --frames is the total:
    // a film that holds as many or more is refused before any work.
    let err = fails(&["render", "--resume", film_s, "--spp", "2", "--frames", "6"]);
    assert!(err.contains("samples_per_frame is '1' there, '2' here"), "{err}");
    for frames in ["2", "3"] {
        let err = fails(&["render", "--resume", film_s, "--frames", frames]);
        assert!(err.contains("holds 3 frames already"), "{err}");
    }
    let err = fails(&["render", "--resume", film_s, "--frames", "6", "--first-frame", "2"]);
    assert!(
        err.contains("--first-frame 2 is inside the frames the film holds (up to 3)"),
        "{err}"
    );
    assert_eq!(std::fs::metadata(&film).unwrap().modified().unwrap(), written);
    let err = fails(&["merge", film_s, "--out", film_s]);
    assert!(err.contains("exists"), "{err}");
    let err = fails(&[
        "reference",
        "--scene",
        "cornell-diffuse",
        "--frames",
        "1",
        "--out",
        film_s,
    ]);
    assert!(err.contains("exists"), "{err}");
}

/// The command an interrupted run's error says goes on (between backticks), as words.
fn printed_resume_command(stderr: &str) -> Vec<String> {
    let line = stderr
        .lines()
        .find(|l| l.contains("goes on"))
        .unwrap_or_else(|| panic!("no resume command: {stderr}"));
    let command = line
        .split('`')
        .nth(1)
        .unwrap_or_else(|| panic!("no command in backticks: {line}"));
    assert!(!command.contains('\''), "a path needing quotes in a test: {command}");
    command.split_whitespace().map(str::to_string).collect()
}

/// Runs the printed command `words` (`lightgraph ...`), which must succeed.
fn run_printed(words: &[String]) {
    assert_eq!(words[0], "lightgraph", "{words:?}");
    let args: Vec<&str> = words[1..].iter().map(String::as_str).collect();
    let run = lightgraph(&args);
    assert!(
        run.status.success(),
        "the printed `{}` failed: {}",
        words.join(" "),
        String::from_utf8_lossy(&run.stderr)
    );
}

/// Waits until the film at `path` holds more than `frames` frames (its checkpoints), while
/// the run `child` goes on.
fn wait_for_frames(child: &mut Child, path: &Path, frames: u64) {
    let started = Instant::now();
    while Film::read(path).map_or(true, |f| f.frames <= frames) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its film held {frames} frames"
        );
        assert!(
            started.elapsed() < Duration::from_secs(300),
            "no film of {frames} frames in 300 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn the_resume_command_a_stopped_timed_run_prints_works() {
    let dir = temp_dir("resume-printed");
    let (film, reference) = (dir.join("timed.exr"), dir.join("reference.exr"));
    // More frames than the 64 a render without --frames makes: the hint must not fall back
    // on that default (it did: "holds N frames, more than --frames 64").
    let mut child = start(&box_render(&[
        "--time",
        "8s",
        "--checkpoint",
        "100ms",
        "--out",
        film.to_str().unwrap(),
    ]));
    wait_for_frames(&mut child, &film, 64);
    let (code, stderr) = interrupt_once_written(child, &film, "INT");
    assert_eq!(code, Some(130), "{stderr}");
    let kept = Film::read(&film).unwrap().frames;
    let command = printed_resume_command(&stderr);
    run_printed(&command);
    assert!(command.contains(&"--time".to_string()), "{command:?}");
    assert!(Film::read(&film).unwrap().frames > kept);
    // A reference likewise.
    let out = reference.to_str().unwrap();
    let args = box_reference(&["--time", "8s", "--checkpoint", "100ms", "--out", out]);
    let (code, stderr) = interrupt_once_written(start(&args), &reference, "TERM");
    assert_eq!(code, Some(143), "{stderr}");
    let kept = Film::read(&reference).unwrap().frames;
    run_printed(&printed_resume_command(&stderr));
    assert!(Film::read(&reference).unwrap().frames > kept);
}

#[test]
fn a_second_signal_says_it_exits_without_writing_and_the_checkpoint_stays_whole() {
    let dir = temp_dir("second-signal");
    let film = dir.join("film.exr");
    let child = start(&box_render(&[
        "--frames",
        "100000",
        "--checkpoint",
        "100ms",
        "--out",
        film.to_str().unwrap(),
    ]));
    let started = Instant::now();
    while !film.exists() {
        assert!(started.elapsed() < Duration::from_secs(300), "no checkpoint in 300 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Two signals at once (of two kinds, which the system never merges into one).
    let pid = child.id();
    let sent = Command::new("sh")
        .args(["-c", &format!("kill -INT {pid}; kill -TERM {pid}")])
        .status()
        .unwrap();
    assert!(sent.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(matches!(out.status.code(), Some(130 | 143)), "{stderr}");
    assert!(
        stderr.contains("a second Ctrl-C exits at once without writing"),
        "{stderr}"
    );
    assert!(
        stderr.contains("second signal") && stderr.contains("exiting at once without writing"),
        "{stderr}"
    );
    // The film on disk is a whole checkpoint.
    let kept = Film::read(&film).unwrap();
    assert!(kept.frames > 0 && kept.frames < 100_000, "{}", kept.frames);
}

#[test]
fn a_command_that_keeps_nothing_at_a_signal_ends_at_the_first() {
    // `bench` has no film to keep: Ctrl-C ends it at once (it used to be told to stop after
    // its frame, which it never looks at, and ran on to its end).
    let dir = temp_dir("bench-signal");
    let out = dir.join("bench");
    let args = [
        "bench",
        "--scene",
        "cornell-diffuse",
        "--layouts",
        "NaivePTsk",
        "--points",
        "8x8x1",
        "--time",
        "60s",
        "--out",
        out.to_str().unwrap(),
    ];
    let mut child = start(&args);
    // Once it renders (its first frame is at most a few seconds away on a loaded machine).
    std::thread::sleep(Duration::from_secs(5));
    assert!(child.try_wait().unwrap().is_none(), "bench ended before the signal");
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let sent_at = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        assert!(
            sent_at.elapsed() < Duration::from_secs(20),
            "bench still runs 20 s after SIGINT"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(2), "{status:?}");
}
