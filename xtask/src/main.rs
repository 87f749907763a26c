//! `cargo xtask render | test`: the two commands of the README, on a fresh machine; and
//! `cargo xtask docs [--check]`, the docs generated from the code (`test` checks them first).
//!
//! `render` and `test` first make sure a Vulkan driver exists: when none is installed, Mesa's software
//! driver (lavapipe, Debian package `mesa-vulkan-drivers`) is installed with apt-get if this
//! process may (root, apt present); otherwise the command to run is printed.

mod docs;

use std::path::Path;
use std::process::{Command, ExitCode};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

const INSTALL: &str = "apt-get install -y --no-install-recommends mesa-vulkan-drivers libvulkan1";

fn usage() -> ExitCode {
    eprintln!(
        "usage: cargo xtask <command> [args]\n\n  render [lightgraph render args]  render the default scene (out/render.exr, out/render.png)\n  test [--assets] [cargo test args]  run the whole test suite (the MPI test where mpirun exists, the Python module's where numpy and pytest do, the assets tier where the asset root does; --assets: fail without it)\n  vulkan                           only make sure a Vulkan driver is installed\n  docs [--check]                   write docs/reference/cli.md, graph-file.md and the declared gaps of docs/estimators/*.md from the code (--check: fail where the committed ones differ; `test` runs it first)\n  imports                          list each crate's import circles (tests/imports; fails on one not allowed)"
    );
    ExitCode::from(2)
}

/// Whether the Vulkan loader and at least one driver manifest are present.
fn vulkan_present() -> bool {
    let loader = [
        "/usr/lib/x86_64-linux-gnu",
        "/usr/lib/aarch64-linux-gnu",
        "/usr/lib64",
        "/usr/lib",
        "/usr/local/lib",
    ]
    .iter()
    .any(|d| Path::new(d).join("libvulkan.so.1").exists());
    let env_driver = ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    let manifests = [
        "/usr/share/vulkan/icd.d",
        "/etc/vulkan/icd.d",
        "/usr/local/share/vulkan/icd.d",
    ]
    .iter()
    .any(|d| {
        std::fs::read_dir(d)
            .map(|mut e| e.any(|f| f.is_ok_and(|f| f.path().extension().is_some_and(|x| x == "json"))))
            .unwrap_or(false)
    });
    loader && (manifests || env_driver)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

fn ensure_vulkan() -> Result<(), String> {
    if vulkan_present() {
        return Ok(());
    }
    let has_apt = Command::new("apt-get")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !(has_apt && is_root()) {
        return Err(format!(
            "no Vulkan driver found. Install Mesa's software Vulkan driver (lavapipe) or a GPU driver, e.g.:\n    sudo apt-get update && sudo {INSTALL}"
        ));
    }
    eprintln!("xtask: no Vulkan driver found; installing Mesa's lavapipe: apt-get update && {INSTALL}");
    let ok = Command::new("apt-get")
        .arg("update")
        .status()
        .is_ok_and(|s| s.success())
        && Command::new("sh")
            .args(["-c", INSTALL])
            .env("DEBIAN_FRONTEND", "noninteractive")
            .status()
            .is_ok_and(|s| s.success());
    if ok && vulkan_present() {
        Ok(())
    } else {
        Err(format!("installing the Vulkan driver failed; run: {INSTALL}"))
    }
}

/// Variables `cargo run` sets for the program it runs (xtask's package, manifest and binary).
const PACKAGE_VARIABLES: [&str; 5] = [
    "CARGO_PKG_",
    "CARGO_MANIFEST_",
    "CARGO_CRATE_",
    "CARGO_BIN_",
    "CARGO_PRIMARY_",
];

/// A cargo command for this process to run, without the variables `cargo run` gave this
/// process: ring's build script reruns when `CARGO_MANIFEST_DIR` or `CARGO_PKG_NAME` changes,
/// so with them every build started here rebuilt ring, rustls, ureq and lightgraph after a
/// plain `cargo` build, and the other way round.
fn cargo_command() -> Command {
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    for (name, _) in std::env::vars_os() {
        if PACKAGE_VARIABLES.iter().any(|p| name.to_string_lossy().starts_with(p)) {
            cmd.env_remove(name);
        }
    }
    cmd
}

fn cargo(args: &[&str], extra: &[String]) -> ExitCode {
    let mut cmd = cargo_command();
    cmd.args(args).args(extra);
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        cmd.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    match cmd.status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(s) => ExitCode::from(s.code().unwrap_or(1).clamp(1, 255) as u8),
        Err(e) => {
            eprintln!("xtask: cannot run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `cargo` arguments of the integration tests, with the suite's packages and profile (so that
/// nothing is built again); the test harness's arguments follow.
const INTEGRATION_TESTS: [&str; 8] = [
    "test",
    "--workspace",
    "--exclude",
    "lightgraph-python",
    "--release",
    "--test",
    "integration",
    "--",
];

/// The tests of persistent threads (threads that take items until none is left) again, with
/// a busy thread on every core: on a loaded CPU some threads start late and the others take
/// more items, which on a driver that caps an invocation's loop iterations (llvmpipe) must
/// neither lose work nor go unreported. Runs the ignored
/// `persistent_thread_layouts_match_at_gpu_sizes` too.
fn loaded_test() -> ExitCode {
    let stop = Arc::new(AtomicBool::new(false));
    let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
    let hogs: Vec<_> = (0..cores)
        .map(|_| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                let mut x = 1u64;
                while !stop.load(Ordering::Relaxed) {
                    x = std::hint::black_box(x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1));
                }
            })
        })
        .collect();
    eprintln!("xtask: the persistent-thread tests again, with {cores} busy threads (a loaded CPU)");
    let filters = ["--include-ignored", "persistent_thread", "lost_work::"].map(String::from);
    let result = cargo(&INTEGRATION_TESTS, &filters);
    stop.store(true, Ordering::Relaxed);
    for hog in hogs {
        let _ = hog.join();
    }
    result
}

/// The MPI test (`render --mpi` across 2 and 3 ranks), built with the `mpi` feature, where
/// `mpirun` is installed; a note otherwise.
fn mpi_test(extra: &[String]) -> ExitCode {
    let found = Command::new("mpirun")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        eprintln!(
            "xtask: no mpirun on the PATH: the MPI test is skipped (Debian: apt-get install openmpi-bin libopenmpi-dev libclang-dev)"
        );
        return ExitCode::SUCCESS;
    }
    cargo(
        &[
            "test",
            "--release",
            "--package",
            "lightgraph",
            "--features",
            "mpi",
            "--test",
            "mpi",
        ],
        extra,
    )
}

/// The asset root the tests read (as lightgraph's `assets::asset_root`): LIGHTGRAPH_ASSETS,
/// else `shared/scenes` beside the repository, when it exists.
fn asset_root() -> Option<std::path::PathBuf> {
    match std::env::var_os("LIGHTGRAPH_ASSETS") {
        Some(dir) => Some(dir.into()),
        None => Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes")).filter(|d| d.is_dir()),
    }
}

/// The tests the assets tier holds at the least (their names hold `shared_assets`): a filter
/// that matched fewer would let the tier pass without running them.
const ASSETS_TIER_TESTS: usize = 7;

/// The assets tier: the integration tests that need the shared assets (ignored in the plain
/// run, which reports them as ignored with the reason; their names hold `shared_assets`), run
/// where the asset root exists; where it does not, a note, or a failure when `required`
/// (`--assets`).
fn assets_tier(required: bool) -> ExitCode {
    let Some(root) = asset_root() else {
        if required {
            eprintln!(
                "xtask: --assets: no asset root (set LIGHTGRAPH_ASSETS or put shared/scenes beside the repository): the assets tier cannot run"
            );
            return ExitCode::FAILURE;
        }
        eprintln!(
            "xtask: no asset root (LIGHTGRAPH_ASSETS, or shared/scenes beside the repository): the assets tier (tests named *shared_assets*, ignored above) is not run"
        );
        return ExitCode::SUCCESS;
    };
    let tier = INTEGRATION_TESTS;
    let listed = cargo_command()
        .args(tier)
        .args(["--ignored", "--list", "shared_assets"])
        .output();
    let count = listed.map_or(0, |o| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| l.ends_with(": test"))
            .count()
    });
    if count < ASSETS_TIER_TESTS {
        eprintln!(
            "xtask: the assets tier lists {count} tests named *shared_assets*, fewer than the {ASSETS_TIER_TESTS} it holds"
        );
        return ExitCode::FAILURE;
    }
    eprintln!("xtask: the assets tier ({count} tests) over {}", root.display());
    let result = cargo(&tier, &["--ignored".to_string(), "shared_assets".to_string()]);
    eprintln!(
        "xtask: not run: the tests named *fetched_assets* (ignored above, with the reason), which read files the developers' shared copy lacks (LivingRoom's Mitsuba meshes); after `lightgraph assets fetch LivingRoom --to ROOT`: LIGHTGRAPH_ASSETS=ROOT cargo test --release --test integration -- --ignored fetched_assets"
    );
    result
}

/// The first Python interpreter (LIGHTGRAPH_PYTHON, python3, /usr/bin/python3) that has
/// numpy and pytest.
fn python_with_pytest() -> Option<String> {
    let candidates = std::env::var("LIGHTGRAPH_PYTHON")
        .into_iter()
        .chain(["python3".into(), "/usr/bin/python3".into()]);
    candidates.into_iter().find(|python| {
        Command::new(python)
            .args(["-c", "import numpy, pytest"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// The Python module's tests (python/tests): builds the module for an interpreter with numpy
/// and pytest, puts it where that interpreter finds it, and runs pytest against the CLI binary
/// of the same build, printing the reason of every skipped test (the notebook's, without
/// nbclient and ipykernel); a note when no such interpreter exists.
fn python_test() -> ExitCode {
    let Some(python) = python_with_pytest() else {
        eprintln!(
            "xtask: no Python with numpy and pytest: the Python module's tests are skipped (Debian: apt-get install python3-numpy python3-pytest)"
        );
        return ExitCode::SUCCESS;
    };
    // SAFETY: xtask is single-threaded; the child cargo reads it.
    unsafe { std::env::set_var("PYO3_PYTHON", &python) };
    let built = cargo(&["build", "--release", "--package", "lightgraph-python"], &[]);
    if built != ExitCode::SUCCESS {
        return built;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), Into::into);
    let module_dir = target.join("python");
    let copied = std::fs::create_dir_all(&module_dir).and_then(|_| {
        std::fs::copy(
            target.join("release/liblightgraph.so"),
            module_dir.join("lightgraph.so"),
        )
    });
    if let Err(e) = copied {
        eprintln!("xtask: cannot put the Python module into {}: {e}", module_dir.display());
        return ExitCode::FAILURE;
    }
    let status = Command::new(&python)
        .args(["-m", "pytest", "-q", "-rs", "python/tests"])
        .current_dir(&root)
        .env("PYTHONPATH", &module_dir)
        .env("LIGHTGRAPH_BIN", target.join("release/lightgraph"))
        .status();
    match status {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("xtask: cannot run {python}: {e}");
            ExitCode::FAILURE
        }
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(command) = args.first() else { return usage() };
    // `cargo xtask render -- ARGS` means `cargo xtask render ARGS` (for `test`, `--` still
    // separates cargo test's arguments from the test harness's).
    let rest = match (command.as_str(), args.get(1).map(String::as_str)) {
        ("render", Some("--")) => &args[2..],
        _ => &args[1..],
    };
    if command == "imports" {
        let check = [
            "test",
            "--release",
            "--package",
            "lightgraph",
            "--test",
            "imports",
            "--",
        ];
        return cargo(&check, &["--nocapture".to_string()]);
    }
    if command == "docs" {
        return docs::run(rest);
    }
    if !matches!(command.as_str(), "render" | "test" | "vulkan") {
        return usage();
    }
    if let Err(e) = ensure_vulkan() {
        eprintln!("xtask: {e}");
        return ExitCode::FAILURE;
    }
    match command.as_str() {
        "render" => {
            // The default film is replaced on a second run; a named --out is protected.
            let force = !rest
                .iter()
                .any(|a| a == "--out" || a.starts_with("--out=") || a == "--resume");
            let mut args = vec!["run", "--release", "--package", "lightgraph", "--", "render"];
            if force {
                args.push("--force");
            }
            cargo(&args, rest)
        }
        "test" => {
            let assets = rest.iter().any(|a| a == "--assets");
            let rest: Vec<String> = rest.iter().filter(|a| *a != "--assets").cloned().collect();
            let rest = rest.as_slice();
            let current = docs::run(&["--check".to_string()]);
            if current != ExitCode::SUCCESS {
                return current;
            }
            let rust = cargo(
                &["test", "--workspace", "--exclude", "lightgraph-python", "--release"],
                rest,
            );
            if rust != ExitCode::SUCCESS {
                return rust;
            }
            if rest.is_empty() || assets {
                let tier = assets_tier(assets);
                if tier != ExitCode::SUCCESS {
                    return tier;
                }
            }
            // Before the MPI test, whose feature rebuilds the crate.
            if rest.is_empty() {
                let loaded = loaded_test();
                if loaded != ExitCode::SUCCESS {
                    return loaded;
                }
            }
            match mpi_test(rest) {
                ExitCode::SUCCESS => python_test(),
                failed => failed,
            }
        }
        _ => ExitCode::SUCCESS,
    }
}
