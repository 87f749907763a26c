//! The HTML reports of `verify`, `compare`, `study`, `bench` and `render --reference` on
//! 16 x 16 images, opened in headless Chromium by tests/browser/check.mjs: no console error
//! and no request off the disk; pixels read back from the canvas equal to the EXRs' values
//! tone-mapped as the PNG previews are; flip, split slider, t-map, plot hover and tables.
//! Without node, Chromium or playwright-core (`npm ci --prefix tests/browser`) the browser
//! part is skipped with a loud reason, and fails instead when LIGHTGRAPH_BROWSER_TESTS=1 (as
//! CI sets it). LIGHTGRAPH_SCREENSHOTS=docs/screenshots saves the docs' screenshots.

use crate::cli::{lightgraph, temp_dir};
use lightgraph::output::read_rgb;
use lightgraph::report::Report;
use lightgraph_scenes::texture::linear_to_srgb8;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The pixels whose tone-mapped values are read back (the images are 16 x 16).
const PIXELS: [(usize, usize); 4] = [(0, 0), (7, 8), (15, 15), (3, 12)];

/// The size every command here renders at.
const RES: [&str; 2] = ["--res", "16x16"];

/// Runs lightgraph with `args`, which must succeed.
fn run(args: &[&str]) {
    let o = lightgraph(args);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// The check of viewer `index`: A and B by label and the values of their EXRs at [`PIXELS`],
/// tone-mapped (exposure 0, as the PNG previews); they must differ somewhere, or a flip
/// would show nothing.
fn viewer(index: usize, a: (&str, &Path), b: (&str, &Path), tmap: bool) -> Value {
    let (wa, _, ra) = read_rgb(a.1).unwrap();
    let (wb, _, rb) = read_rgb(b.1).unwrap();
    assert_eq!(wa, wb);
    let mut check = viewer_of(index, (a.0, &ra), (b.0, &rb), wa as usize);
    check["tmap"] = json!(tmap);
    check
}

/// The check of viewer `index` showing images `a` and `b` (label and pixels) of `width`.
fn viewer_of(index: usize, a: (&str, &[[f32; 3]]), b: (&str, &[[f32; 3]]), width: usize) -> Value {
    let tone = |rgb: &[[f32; 3]], (x, y): (usize, usize)| rgb[y * width + x].map(linear_to_srgb8);
    let pixels: Vec<Value> = PIXELS
        .iter()
        .map(|&p| json!({"x": p.0, "y": p.1, "a": tone(a.1, p), "b": tone(b.1, p)}))
        .collect();
    assert!(
        pixels.iter().any(|p| p["a"] != p["b"]),
        "{} and {} look the same",
        a.0,
        b.0
    );
    json!({"index": index, "a": a.0, "b": b.0, "pixels": pixels})
}

/// A ramp across a 16 x 16 image, and a flat colour.
fn ramp_and_flat() -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let ramp = (0..256)
        .map(|i| [i as f32 / 255.0, 0.5, 1.0 - i as f32 / 400.0])
        .collect();
    (ramp, vec![[0.25f32, 2.0, 0.01]; 256])
}

/// The first run's label in a comparison's curves.csv.
fn first_run(curves: &Path) -> String {
    let text = std::fs::read_to_string(curves).unwrap();
    let row = text.lines().nth(1).expect("a curve");
    row.split(',').next().unwrap().to_string()
}

/// Where the screenshot of report `name` goes: LIGHTGRAPH_SCREENSHOTS/name.png when set (a
/// folder relative to the repository), else a temporary folder.
pub fn screenshot(name: &str) -> PathBuf {
    match std::env::var_os("LIGHTGRAPH_SCREENSHOTS") {
        Some(dir) => Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(dir)
            .join(format!("{name}.png")),
        None => temp_dir(&format!("report-{name}-screenshot")).join(format!("{name}.png")),
    }
}

/// What the browser check needs and is missing, if anything.
pub fn missing_browser(root: &Path) -> Option<String> {
    if Command::new("node").arg("--version").output().is_err() {
        return Some("node is not installed".into());
    }
    let chromium = std::env::var("LIGHTGRAPH_CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !Path::new(&chromium).exists() {
        return Some(format!("no Chromium at {chromium} (apt-get install chromium)"));
    }
    if !root.join("tests/browser/node_modules/playwright-core").exists() {
        return Some("playwright-core is not installed (npm ci --prefix tests/browser)".into());
    }
    None
}

/// Runs tests/browser/check.mjs on `reports` (see its header for their form), which must pass.
fn check_in_browser(name: &str, reports: Vec<Value>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Some(missing) = missing_browser(root) {
        let required = std::env::var("LIGHTGRAPH_BROWSER_TESTS").is_ok_and(|v| v == "1");
        assert!(!required, "LIGHTGRAPH_BROWSER_TESTS=1, but {missing}");
        eprintln!("\n*** skipped: the browser check of the {name} report: {missing} ***\n");
        return;
    }
    let spec = temp_dir(&format!("report-{name}-check")).join("browser-check.json");
    std::fs::write(&spec, json!({ "reports": reports }).to_string()).unwrap();
    let o = Command::new("node")
        .arg(root.join("tests/browser/check.mjs"))
        .arg(&spec)
        .output()
        .expect("node runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        o.status.success(),
        "the browser check of the {name} report failed:\n{text}"
    );
}

#[test]
fn verify_report_shows_the_runs_and_their_t_maps() {
    let out = temp_dir("report-verify");
    let o = out.to_str().unwrap();
    let args = [
        "--scenes",
        "cornell-diffuse",
        "--graphs",
        "pt,lt",
        "--frames",
        "16",
        "--batches",
        "4",
    ];
    // Undecided at this budget (exit status 1); the report is written all the same.
    let run = lightgraph(&[&["verify"], &args[..], &RES, &["--block", "8", "--out", o]].concat());
    assert!(!String::from_utf8_lossy(&run.stderr).contains("panicked"));
    let html = out.join("report.html");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains(&html.display().to_string()), "{stdout}");
    let scene = out.join("cornell-diffuse");
    let check = viewer(0, ("pt", &scene.join("pt.exr")), ("lt", &scene.join("lt.exr")), true);
    check_in_browser(
        "verify",
        vec![
            json!({"html": html, "screenshot": screenshot("verify"), "mode": "tmap", "tables": 2, "viewers": [check]}),
        ],
    );
}

#[test]
fn compare_and_render_reports_show_error_against_time_and_the_images() {
    let dir = temp_dir("report-compare");
    let reference = dir.join("reference.exr");
    let scene = ["--scene", "cornell-diffuse"];
    let r = reference.to_str().unwrap();
    run(&[
        &["reference"],
        &scene[..],
        &RES,
        &["--graph", "pt", "--frames", "8", "--out", r],
    ]
    .concat());
    let cmp = dir.join("compare");
    run(&[
        "compare",
        "--runs",
        "pt,lt",
        "--reference",
        r,
        "--time",
        "1s",
        "--out",
        cmp.to_str().unwrap(),
    ]);
    let film = dir.join("render.exr");
    let f = film.to_str().unwrap();
    run(&[
        &["render"],
        &scene[..],
        &RES,
        &["--frames", "16", "--reference", r, "--out", f],
    ]
    .concat());
    let label = first_run(&cmp.join("curves.csv"));
    let run_exr = cmp.join(lightgraph::compare::file_stem(&label)).with_extension("exr");
    let compare = json!({
        "html": cmp.join("report.html"), "screenshot": screenshot("compare"), "tables": 1, "plots": 1,
        "viewers": [viewer(0, ("reference", &reference), (&label, &run_exr), false)],
    });
    let render = json!({
        "html": dir.join("render.html"), "screenshot": screenshot("render"), "plots": 1,
        "viewers": [viewer(0, ("render.exr", &film), ("reference", &reference), false)],
    });
    check_in_browser("compare and render", vec![compare, render]);
}

#[test]
fn study_report_shows_each_scene() {
    let out = temp_dir("report-study");
    let o = out.to_str().unwrap();
    let args = [
        "--scenes",
        "cornell-diffuse",
        "--estimators",
        "pt:NaivePTsk,lt",
        "--time",
        "1s",
    ];
    let reference = [
        "--reference-graph",
        "pt",
        "--reference-frames",
        "4",
        "--layout-time",
        "30ms",
    ];
    run(&[&["study"], &args[..], &reference, &RES, &["--out", o]].concat());
    let label = first_run(&out.join("cornell-diffuse/curves.csv"));
    let run_exr = out.join("cornell-diffuse").join(lightgraph::compare::file_stem(&label));
    let reference = out.join("references/cornell-diffuse.exr");
    let check = viewer(
        0,
        ("reference", &reference),
        (&label, &run_exr.with_extension("exr")),
        false,
    );
    let study = json!({
        "html": out.join("report.html"), "screenshot": screenshot("study"), "tables": 1, "plots": 1,
        "viewers": [check],
    });
    check_in_browser("study", vec![study]);
}

#[test]
fn bench_report_shows_its_tables_and_plot() {
    let out = temp_dir("report-bench");
    let args = ["--scene", "cornell-diffuse", "--layouts", "NaivePTsk,RegenerationPTsk"];
    let sweep = [
        "--points",
        "16x16x1,32x32x1",
        "--time",
        "100ms",
        "--out",
        out.to_str().unwrap(),
    ];
    run(&[&["bench"], &args[..], &sweep].concat());
    let bench = json!({"html": out.join("report.html"), "screenshot": screenshot("bench"), "tables": 2, "plots": 1});
    check_in_browser("bench", vec![bench]);
}

#[test]
fn large_images_load_from_beside_the_report() {
    let dir = temp_dir("report-beside");
    let (ramp, flat) = ramp_and_flat();
    let html = dir.join("beside.html");
    let mut report = Report::new("beside");
    report
        .inline_limit(0)
        .viewer("two")
        .image("ramp", 16, 16, &ramp)
        .image("flat", 16, 16, &flat);
    report.write(&html).unwrap();
    assert!(dir.join("beside.data/image-1.js").exists());
    let check = viewer_of(0, ("ramp", &ramp), ("flat", &flat), 16);
    check_in_browser("beside", vec![json!({"html": html, "viewers": [check]})]);
}

/// A notebook shows several reports in one page ([`Report::to_html`] each): each keeps its
/// own images, though their labels are the same.
#[test]
fn two_reports_in_one_page_keep_their_images_apart() {
    let (ramp, flat) = ramp_and_flat();
    let page = |x: &[[f32; 3]], y: &[[f32; 3]]| {
        let mut report = Report::new("one of two");
        report.viewer("x and y").image("x", 16, 16, x).image("y", 16, 16, y);
        report.to_html()
    };
    let html = temp_dir("report-two").join("two.html");
    std::fs::write(&html, page(&ramp, &flat) + &page(&flat, &ramp)).unwrap();
    let first = viewer_of(0, ("x", &ramp), ("y", &flat), 16);
    let second = viewer_of(1, ("x", &flat), ("y", &ramp), 16);
    check_in_browser("two", vec![json!({"html": html, "viewers": [first, second]})]);
}
