//! Nothing lost before it starts: every command checks its outputs before any work (each
//! can be written, and an earlier run's files, the PNG beside a film included, are replaced
//! only with --force), with one line naming the path and the problem; inputs that are not
//! what they claim (a PNG for a film, a folder for a scene, garbage for a .glb, an image too
//! large for the adapter) are named as what they are, with the option to change.

use crate::cli::{fails, lightgraph, temp_dir};
use std::path::{Path, PathBuf};

/// The diffuse box at 8×8, one frame.
const BOX: [&str; 6] = ["--scene", "cornell-diffuse", "--res", "8x8", "--frames", "1"];

/// A film of the [`BOX`] at `path`.
fn film(path: &Path) {
    let run = lightgraph(&[&["render"], &BOX[..], &["--out", path.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
}

/// Each command with arguments of a small run (the reference `reference` for `compare`, the
/// film `film` for `merge`), whose outputs are a file (an EXR with its PNG) or a folder.
fn commands<'a>(reference: &'a str, film: &'a str) -> Vec<(&'static str, Vec<&'a str>, bool)> {
    let tiny = ["--res", "8x8"];
    vec![
        ("render", [&["render", "--frames", "1"], &tiny[..]].concat(), true),
        ("reference", [&["reference", "--frames", "1"], &tiny[..]].concat(), true),
        ("merge", vec!["merge", film], true),
        (
            "compare",
            vec!["compare", "--runs", "pt", "--reference", reference, "--time", "1s"],
            false,
        ),
        (
            "study",
            [
                &[
                    "study",
                    "--scenes",
                    "cornell-diffuse",
                    "--estimators",
                    "pt",
                    "--reference-frames",
                    "1",
                ],
                &tiny[..],
            ]
            .concat(),
            false,
        ),
        (
            "verify",
            [
                &[
                    "verify",
                    "--scenes",
                    "cornell-diffuse",
                    "--graphs",
                    "pt,bpt-naive",
                    "--frames",
                    "2",
                ],
                &tiny[..],
            ]
            .concat(),
            false,
        ),
        ("bench", vec!["bench", "--points", "8x8x1", "--time", "100ms"], false),
        (
            "stress",
            vec!["stress", "--only", "degenerate", "--graphs", "pt"],
            false,
        ),
        ("export", vec!["export"], false),
    ]
}

/// Runs `args` with `--out out` (and `extra`), which must fail at once: one line of stderr,
/// the error (no GPU header, no render, the error not printed twice), holding `needle`.
fn refused_at_once(args: &[&str], out: &Path, extra: &[&str], needle: &str) -> String {
    let argv = [args, &["--out", out.to_str().unwrap()], extra].concat();
    let err = fails(&argv);
    assert!(err.contains(needle), "{argv:?}: '{needle}' not in {err}");
    assert_eq!(err.trim().lines().count(), 1, "{argv:?}: more than the error: {err}");
    err
}

/// A reference and a film for the commands that read one.
fn inputs(dir: &Path) -> (PathBuf, PathBuf) {
    let (reference, input) = (dir.join("ref.exr"), dir.join("film.exr"));
    let run = lightgraph(&[&["reference"], &BOX[..], &["--out", reference.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    film(&input);
    (reference, input)
}

#[test]
fn an_out_that_cannot_be_written_fails_every_command_before_any_work() {
    let dir = temp_dir("unwritable");
    let (reference, input) = inputs(&dir);
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    for (name, args, is_film) in commands(reference.to_str().unwrap(), input.to_str().unwrap()) {
        let leaf = if is_film { "x.exr" } else { "out" };
        // A parent that is a file.
        let out = file.join("sub").join(leaf);
        let err = refused_at_once(&args, &out, &[], "is a file, not a folder");
        assert!(err.contains(&file.display().to_string()), "{name}: {err}");
        // A folder no file can be created in (even by root).
        let out = Path::new("/proc").join(leaf);
        refused_at_once(&args, &out, &[], "cannot write into /proc");
    }
}

#[test]
fn a_read_only_folder_is_refused_where_the_system_refuses_writing() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir("read-only").join("locked");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    let out = dir.join("x.exr");
    // Root writes into a read-only folder; anyone else cannot: the render does as the system.
    let writable = std::fs::write(dir.join("probe"), "").is_ok();
    let _ = std::fs::remove_file(dir.join("probe"));
    let args = [&["render"], &BOX[..]].concat();
    if writable {
        let run = lightgraph(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        assert!(out.is_file());
    } else {
        refused_at_once(&args, &out, &[], "cannot write into");
    }
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn an_earlier_runs_output_is_replaced_only_with_force() {
    let dir = temp_dir("earlier");
    let (reference, input) = inputs(&dir);
    let earlier = "an earlier run's output";
    for (name, args, is_film) in commands(reference.to_str().unwrap(), input.to_str().unwrap()) {
        let folder = dir.join(name);
        std::fs::create_dir_all(&folder).unwrap();
        // A film's PNG preview alone counts; a folder's file of the command's own.
        let (out, held) = match name {
            _ if is_film => (folder.join("x.exr"), folder.join("x.png")),
            "compare" => (folder.clone(), folder.join("settings.txt")),
            "study" => (folder.clone(), folder.join("summary.md")),
            "verify" => (folder.clone(), folder.join("verify.md")),
            "bench" => (folder.clone(), folder.join("bench.csv")),
            "stress" => (folder.clone(), folder.join("stress.md")),
            _ => (folder.clone(), folder.join("meshes")),
        };
        std::fs::write(&held, earlier).unwrap();
        let err = refused_at_once(&args, &out, &[], "--force");
        assert!(
            err.contains(&held.file_name().unwrap().to_string_lossy().to_string()),
            "{name}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(&held).unwrap(),
            earlier,
            "{name} changed {}",
            held.display()
        );
        if is_film {
            assert!(!out.exists(), "{name} wrote {}", out.display());
        }
    }
    // With --force the render replaces the PNG (and merges, references likewise).
    let out = dir.join("render").join("x.exr");
    let run = lightgraph(
        &[
            &commands("", "")[0].1[..],
            &["--scene", "cornell-diffuse", "--out", out.to_str().unwrap(), "--force"],
        ]
        .concat(),
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert_ne!(std::fs::read(out.with_extension("png")).unwrap(), earlier.as_bytes());
}

#[test]
fn an_earlier_html_report_counts_as_output() {
    let dir = temp_dir("earlier-report");
    let (reference, _) = inputs(&dir);
    let earlier = "an earlier run's report";
    // render --reference writes X.html beside the film.
    let out = dir.join("render").join("x.exr");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    std::fs::write(out.with_extension("html"), earlier).unwrap();
    let args = [&["render"], &BOX[..], &["--reference", reference.to_str().unwrap()]].concat();
    refused_at_once(&args, &out, &[], "x.html exists");
    // verify's folder holding only its report.html.
    let folder = dir.join("verify");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("report.html"), earlier).unwrap();
    let args = [
        "verify",
        "--scenes",
        "cornell-diffuse",
        "--graphs",
        "pt,lt",
        "--frames",
        "2",
    ];
    refused_at_once(&args, &folder, &[], "report.html");
    assert_eq!(std::fs::read_to_string(folder.join("report.html")).unwrap(), earlier);
}

#[test]
fn export_into_an_earlier_export_is_refused_and_force_leaves_no_stale_mesh() {
    let dir = temp_dir("export-again").join("scene");
    let o = dir.to_str().unwrap();
    let run = lightgraph(&["export", "--scene", "cornell-diffuse", "--out", o]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let (stale, own) = (dir.join("meshes").join("stale.ply"), dir.join("notes.txt"));
    std::fs::write(&stale, "a mesh of another scene").unwrap();
    std::fs::write(&own, "the user's").unwrap();
    let err = fails(&["export", "--scene", "cornell-diffuse", "--out", o]);
    assert!(err.contains("scene.xml") && err.contains("--force"), "{err}");
    assert!(stale.exists());
    let run = lightgraph(&["export", "--scene", "cornell-diffuse", "--out", o, "--force"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(!stale.exists(), "the earlier export's mesh is still there");
    assert!(dir.join("scene.xml").is_file() && dir.join("meshes").join("shape0.ply").is_file());
    assert_eq!(std::fs::read_to_string(&own).unwrap(), "the user's");
}

#[test]
fn inputs_that_are_not_what_they_claim_are_named_as_what_they_are() {
    let dir = temp_dir("not-what-they-claim");
    let out = dir.join("x.exr");
    let o = out.to_str().unwrap();
    // A PNG given for a film: to merge, to resume.
    let png = dir.join("film.png");
    film(&dir.join("film.exr"));
    let p = png.to_str().unwrap();
    for args in [
        &["merge", p, "--out", o][..],
        &["render", "--resume", p],
        &["reference", "--resume", p, "--frames", "1"],
    ] {
        let err = fails(args);
        assert!(
            err.contains(p) && err.contains("a PNG image, not an EXR film written by lightgraph"),
            "{args:?}: {err}"
        );
    }
    // A folder as --scene.
    let err = fails(&["render", "--scene", dir.to_str().unwrap(), "--res", "8x8", "--out", o]);
    assert!(
        err.contains(&format!("{} is a folder, not a scene", dir.display())),
        "{err}"
    );
    // Garbage as a .glb.
    let glb = dir.join("garbage.glb");
    std::fs::write(&glb, [0x42u8; 64]).unwrap();
    let err = fails(&["render", "--scene", glb.to_str().unwrap(), "--res", "8x8", "--out", o]);
    assert!(
        err.contains(&format!("{}: not a valid glTF binary", glb.display())),
        "{err}"
    );
    // An image whose film the adapter cannot bind in one buffer (lavapipe binds 128 MiB; the
    // film's accumulation takes 16 bytes a pixel): the error names --res, the limit and a
    // size that fits.
    let err = fails(&["render", "--res", "4096x4096", "--frames", "1", "--out", o]);
    assert!(
        err.contains("--res")
            && err.contains("4096x4096")
            && err.contains("binds in one buffer")
            && err.contains("at most about"),
        "{err}"
    );
    assert!(!out.exists());
}
