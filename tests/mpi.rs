//! Rendering across MPI ranks (`render --mpi`, cargo feature `mpi`): 2 and 3 ranks of
//! `mpirun` on this machine's adapter give the film of one process rendering the same frames:
//! the merged sample count is the total, the frame ranges one run's, the image equal to float
//! rounding. Run by `cargo xtask test` where `mpirun` exists (CI installs Open MPI):
//! `cargo test --release --features mpi --test mpi`.
#![cfg(feature = "mpi")]

use lightgraph::film::Film;
use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_lightgraph");

/// A fresh folder of this test process named `name`.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lightgraph-mpi-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `lightgraph render` of 40 frames (seed 3, the diffuse box at 16x12) into `out`, through
/// `mpirun -n ranks` when given.
fn render(ranks: Option<u32>, out: &std::path::Path) -> Film {
    let args = ["--scene", "cornell-diffuse", "--frames", "40"];
    render_with(ranks, &args, out)
}

/// `lightgraph render` at 16x12 with seed 3 and `extra` arguments into `out`, through
/// `mpirun -n ranks` when given.
fn render_with(ranks: Option<u32>, extra: &[&str], out: &std::path::Path) -> Film {
    let args = [
        &[
            "render",
            "--res",
            "16x12",
            "--seed",
            "3",
            "--out",
            out.to_str().unwrap(),
        ],
        extra,
    ]
    .concat();
    let output = match ranks {
        None => Command::new(BIN).args(args).output().unwrap(),
        Some(n) => Command::new("mpirun")
            .args(["--oversubscribe", "--allow-run-as-root", "-n", &n.to_string(), BIN])
            .args(args)
            .arg("--mpi")
            .output()
            .expect("mpirun (Open MPI) on the PATH"),
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{ranks:?} ranks: {stderr}");
    if let Some(n) = ranks {
        assert!(stderr.contains(&format!("on {n} ranks")), "{stderr}");
    }
    Film::read(out).unwrap()
}

#[test]
fn ranks_together_render_the_film_of_one_process() {
    let d = dir("pt");
    let one = render(None, &d.join("one.exr"));
    for n in [2, 3] {
        let film = render(Some(n), &d.join(format!("ranks-{n}.exr")));
        assert_eq!((film.frames, film.ranges.clone()), (40, vec![(0, 40)]), "{n} ranks");
        assert_eq!(film.samples_per_pixel(), one.samples_per_pixel());
        let worst = largest_difference(&film, &one);
        assert!(worst < 1e-5, "{n} ranks differ from one process by {worst:.2e}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The largest difference of two films' means relative to the larger (floored at 1e-3).
fn largest_difference(a: &Film, b: &Film) -> f64 {
    a.mean()
        .iter()
        .zip(&b.mean())
        .flat_map(|(p, q)| {
            (0..3).map(move |c| (p[c] - q[c]).abs() as f64 / p[c].abs().max(q[c].abs()).max(1e-3) as f64)
        })
        .fold(0.0, f64::max)
}

/// LVC-BPT measures its average light sub-path length before the first frame: rank 0 measures
/// it and gives it to every rank, and the film records it, so the ranks render one estimator
/// and the film equals a process given the same value (to the rounding of the splats' atomic
/// float sums: 2e-4, as tests/integration/shards.rs explains).
#[test]
fn ranks_share_rank_zeros_measured_constant() {
    let d = dir("lvc");
    let base = ["--scene", "cornell-glossy-point", "--graph", "bpt-lvc", "--frames", "8"];
    let ranks = render_with(Some(2), &base, &d.join("ranks.exr"));
    let recorded = ranks.info.get("measured").cloned();
    let measured = recorded
        .clone()
        .filter(|m| m.starts_with("LVC_AVERAGE_LENGTH="))
        .unwrap_or_else(|| panic!("the film does not record the measured constant: {recorded:?}"));
    let one = render_with(None, &[&base[..], &["--set", &measured]].concat(), &d.join("one.exr"));
    assert_eq!(one.info.get("measured"), recorded.as_ref());
    let worst = largest_difference(&ranks, &one);
    assert!(worst < 2e-4, "2 ranks differ from one process by {worst:.2e}");
    std::fs::remove_dir_all(&d).ok();
}

/// A run across ranks on a time budget: the ranks stop by the clock, each after a whole block,
/// and the film holds every block the ranks rendered (reduced once, at the end). Where the
/// ranks' blocks make one run's first frames, the film equals one process's render of them.
#[test]
fn a_timed_run_across_ranks_holds_every_rank_s_blocks() {
    let d = dir("timed");
    let film = render_with(
        Some(2),
        &["--scene", "cornell-diffuse", "--time", "1s"],
        &d.join("two.exr"),
    );
    assert!(
        film.frames > 0 && film.frames.is_multiple_of(16),
        "{} frames: not whole blocks of 16",
        film.frames
    );
    let blocks: u64 = film.ranges.iter().map(|r| r.1 - r.0).sum();
    assert_eq!(blocks, film.frames, "ranges {:?}", film.ranges);
    assert_eq!(film.info.get("ranks").map(String::as_str), Some("2"));
    if film.ranges.len() == 1 {
        let frames = film.frames.to_string();
        let one = render_with(
            None,
            &["--scene", "cornell-diffuse", "--frames", &frames],
            &d.join("one.exr"),
        );
        let worst = largest_difference(&film, &one);
        assert!(
            worst < 1e-5,
            "2 ranks on a clock differ from one process by {worst:.2e}"
        );
    }
    std::fs::remove_dir_all(&d).ok();
}
