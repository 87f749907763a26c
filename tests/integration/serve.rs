//! `render --serve`: the live view in a browser. A 16 x 16 render serves its film while it
//! renders (the status's version grows, the film is the size of the image) and a watching page
//! gets the last film before the process ends, equal to the EXR written: over HTTP, and in
//! headless Chromium (tests/browser/live.mjs, which needs what the report tests need and is
//! skipped or required as they are).

use crate::cli::temp_dir;
use crate::report::{missing_browser, screenshot};
use lightgraph::output::read_rgb;
use lightgraph_scenes::texture::linear_to_srgb8;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The pixels the browser reads back.
const PIXELS: [(usize, usize); 3] = [(0, 0), (8, 7), (15, 15)];

/// Starts a 16 x 16 render of `seconds` serving at a free port, its film at `out`, with the
/// further options `more`; returns the process and the page's URL (read from its stderr,
/// which is drained on).
fn serving_render(out: &Path, seconds: &str, more: &[&str]) -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args([
            "render",
            "--scene",
            "cornell-diffuse",
            "--res",
            "16x16",
            "--time",
            seconds,
        ])
        .args(more)
        .args(["--serve", "127.0.0.1:0", "--out"])
        .arg(out)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let (send, receive) = mpsc::channel();
    let stderr = child.stderr.take().expect("piped");
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            eprintln!("render: {line}");
            if let Some(url) = line.strip_prefix("live view at ") {
                let _ = send.send(url.to_string());
            }
        }
    });
    let url = receive
        .recv_timeout(Duration::from_secs(300))
        .expect("the render says where it serves");
    (child, url)
}

fn get(url: &str) -> Vec<u8> {
    ureq::get(url)
        .call()
        .expect("the server answers")
        .body_mut()
        .read_to_vec()
        .unwrap()
}

fn status(url: &str) -> Value {
    serde_json::from_slice(&get(&format!("{url}status.json"))).unwrap()
}

fn floats(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// Polls the status until `done` holds, for at most five minutes.
fn wait_for(url: &str, mut done: impl FnMut(&Value) -> bool) -> Value {
    let started = Instant::now();
    loop {
        let s = status(url);
        if done(&s) {
            return s;
        }
        assert!(started.elapsed() < Duration::from_secs(300), "still {s} after 300 s");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn render_serves_its_film_as_it_renders_and_the_last_one_equals_the_exr() {
    let out = temp_dir("serve").join("live.exr");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let browser = missing_browser(root);
    // With a browser, the render runs until the page has watched it (however long Chromium
    // takes to start on a busy machine) and is then stopped by SIGINT; without one, 8 s.
    let seconds = if browser.is_none() { "600s" } else { "8s" };
    let (mut child, url) = serving_render(&out, seconds, &[]);
    let page = String::from_utf8(get(&url)).unwrap();
    assert!(
        page.contains("lightgraphLiveSources") && page.contains("film.f32"),
        "{page}"
    );
    let first = wait_for(&url, |s| s["frames"].as_u64() > Some(0));
    assert_eq!(
        (first["width"].as_u64(), first["height"].as_u64()),
        (Some(16), Some(16))
    );
    let film = floats(&get(&format!("{url}film.f32")));
    assert_eq!(film.len(), 16 * 16 * 3);
    assert!(film.iter().all(|v| v.is_finite()) && film.iter().any(|&v| v > 0.0));
    let later = wait_for(&url, |s| s["version"].as_u64() > first["version"].as_u64());
    assert!(
        later["frames"].as_u64() > first["frames"].as_u64(),
        "{first} then {later}"
    );
    let (w, _, exr) = match browser {
        None => {
            let points: Vec<String> = PIXELS.iter().map(|(x, y)| format!("{x},{y}")).collect();
            let mut node = Command::new("node")
                .arg(root.join("tests/browser/live.mjs"))
                .args([&url, &points.join(";")])
                .arg(screenshot("serve"))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("node runs");
            let mut lines = BufReader::new(node.stdout.take().expect("piped")).lines();
            let watching = lines.next().and_then(Result::ok);
            if watching.as_deref() == Some("watching") {
                let sent = Command::new("kill")
                    .args(["-INT", &child.id().to_string()])
                    .status()
                    .expect("kill runs");
                assert!(sent.success());
            }
            let rest: Vec<String> = lines.map_while(Result::ok).collect();
            let o = node.wait_with_output().expect("node ends");
            let stdout = rest.join("\n");
            assert!(
                o.status.success() && watching.as_deref() == Some("watching"),
                "{watching:?} {stdout}{}",
                String::from_utf8_lossy(&o.stderr)
            );
            // Stopped by SIGINT: the film written, the signal's exit status.
            assert_eq!(child.wait().unwrap().code(), Some(130));
            let shown: Value = serde_json::from_str(&stdout).unwrap();
            let (w, h, exr) = read_rgb(&out).unwrap();
            for (i, &(x, y)) in PIXELS.iter().enumerate() {
                let expected = exr[y * w as usize + x].map(linear_to_srgb8);
                assert_eq!(shown["pixels"][i], serde_json::json!(expected), "pixel ({x}, {y})");
            }
            (w, h, exr)
        }
        Some(missing) => {
            let required = std::env::var("LIGHTGRAPH_BROWSER_TESTS").is_ok_and(|v| v == "1");
            assert!(!required, "LIGHTGRAPH_BROWSER_TESTS=1, but {missing}");
            eprintln!("\n*** skipped: the browser part of the live view's test: {missing} ***\n");
            wait_for(&url, |s| s["finished"] == true);
            let last = floats(&get(&format!("{url}film.f32")));
            assert!(child.wait().unwrap().success());
            let (w, h, exr) = read_rgb(&out).unwrap();
            assert_eq!(last, exr.iter().flatten().copied().collect::<Vec<f32>>());
            (w, h, exr)
        }
    };
    assert_eq!((w, exr.len()), (16, 256));
}

/// A checkpoint after every batch (1 ms apart) moves the GPU's sums into the film each time:
/// the frames served while rendering are still the run's (the "frame N" of its progress
/// line), not the film's and the session's added (twice as many).
#[test]
fn the_served_frames_count_the_frames_a_checkpoint_absorbed_once() {
    let out = temp_dir("serve-checkpoint").join("live.exr");
    let (mut child, url) = serving_render(&out, "3s", &["--checkpoint", "1ms"]);
    let mut rendering = Vec::new();
    let last = wait_for(&url, |s| {
        if s["finished"] != true && s["frames"].as_u64() > Some(0) {
            rendering.push(s.clone());
        }
        s["finished"] == true
    });
    get(&format!("{url}film.f32"));
    assert!(child.wait().unwrap().success());
    assert!(!rendering.is_empty(), "no update while rendering before {last}");
    for s in rendering.iter().chain([&last]) {
        let line = s["status"].as_str().expect("a progress line");
        let frame = line.strip_prefix("frame ").and_then(|l| l.split(' ').next());
        assert_eq!(s["frames"].as_u64().map(|f| f.to_string()).as_deref(), frame, "{s}");
    }
}

#[test]
fn a_serve_address_in_use_fails_before_rendering() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = taken.local_addr().unwrap().to_string();
    let out = temp_dir("serve-taken").join("x.exr");
    let o = crate::cli::lightgraph(&[
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "16x16",
        "--serve",
        &address,
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains(&address), "{stderr}");
    assert!(!out.exists(), "nothing is written when the address cannot be served");
}
