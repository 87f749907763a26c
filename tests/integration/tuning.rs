//! Tuning profiles on the command line (docs/tuning.md): `explain` shows a layout's knobs from
//! the adapter's profile, none with `--tuning none`, a profile of one's own from a file; a bad
//! profile is a usage error before any work. That the knobs change no image is tested in
//! layouts.rs (the renders with and without the profile).

use crate::cli::{lightgraph, temp_dir};
use crate::options::usage_error;

/// `explain`'s stdout for NaivePTsk at 16x16 with `tuning` (None: the default).
fn explain(tuning: Option<&str>) -> String {
    let mut args = vec!["explain", "--graph", "pt", "--layout", "NaivePTsk", "--res", "16x16"];
    args.extend(tuning.map(|t| ["--tuning", t]).into_iter().flatten());
    let out = lightgraph(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn explain_shows_the_profiles_knobs_and_none_with_tuning_none() {
    let tuned = explain(None);
    assert!(
        tuned.contains("tuning profile default: loop guards off, CWBVH_CHILD_SCAN=true (docs/lab/traversal.md#"),
        "{tuned}"
    );
    assert!(tuned.contains("loop guards off"), "{tuned}");
    let h100 = explain(Some("nvidia-h100"));
    assert!(h100.contains("tuning profile nvidia-h100: loop guards off"), "{h100}");
    let plain = explain(Some("none"));
    assert!(!plain.contains("tuning profile"), "{plain}");
    assert!(
        plain.contains("loop guards on") && !plain.contains("loop guards off"),
        "{plain}"
    );
}

#[test]
fn a_profile_of_ones_own_is_taken_from_its_file() {
    let dir = temp_dir("tuning-own");
    let path = dir.join("mine.ron");
    std::fs::write(
        &path,
        "(\n    like: \"default\",\n    layouts: {\"pt\": {\"NaivePTsk\": (threads: 4096, workgroup_size: 128, why: \"a test\")}},\n)\n",
    )
    .unwrap();
    let mine = explain(Some(path.to_str().unwrap()));
    assert!(
        mine.contains("tuning profile mine: 4096 threads, workgroup 128 (a test)"),
        "{mine}"
    );
    assert!(mine.contains("workgroup 128"), "{mine}");
}

#[test]
fn a_bad_profile_is_an_error_before_any_work() {
    let dir = temp_dir("tuning-bad");
    let out = dir.join("out.exr");
    let out = out.to_str().unwrap();
    let render = |tuning: &str| {
        usage_error(&[
            "render", "--res", "8x8", "--frames", "1", "--tuning", tuning, "--out", out,
        ])
    };
    let unknown = render("amd-rx-7900");
    assert!(
        unknown.contains("no built-in tuning profile 'amd-rx-7900'") && unknown.contains("nvidia-h100"),
        "{unknown}"
    );
    let broken = dir.join("broken.ron");
    std::fs::write(&broken, "(\n    adapters: [\"X\"],\n    loop_guards: false,\n)\n").unwrap();
    let e = render(broken.to_str().unwrap());
    assert!(e.contains("broken.ron:3:"), "{e}");
    let wrong = dir.join("wrong.ron");
    std::fs::write(&wrong, "(layouts: {\"pt\": {\"NaivePTzz\": (loop_guards: false)}})\n").unwrap();
    let e = render(wrong.to_str().unwrap());
    assert!(e.contains("graph 'pt' has no layout 'NaivePTzz'"), "{e}");
    assert!(!std::path::Path::new(out).exists(), "nothing is rendered");
}
