//! Rendering across MPI ranks (`render --mpi`, cargo feature `mpi`): 2 and 3 ranks of
//! `mpirun` on this machine's adapter give the film of one process rendering the same frames:
//! the merged sample count is the total, the frame ranges one run's, the image equal to float
//! rounding. Run by `cargo xtask test` where `mpirun` exists (CI installs Open MPI):
//! `cargo test --release --features mpi --test mpi`.
#![cfg(feature = "mpi")]

use lightgraph::reference::Reference;
use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_lightgraph");

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("lightgraph-mpi-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `lightgraph render` of 40 frames (seed 3, the diffuse box at 16x12) into `out`, through
/// `mpirun -n ranks` when given.
fn render(ranks: Option<u32>, out: &std::path::Path) -> Reference {
    let args = [
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "16x12",
        "--frames",
        "40",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ];
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
    Reference::read(out).unwrap()
}

#[test]
fn ranks_together_render_the_film_of_one_process() {
    let d = dir();
    let one = render(None, &d.join("one.exr"));
    for n in [2, 3] {
        let film = render(Some(n), &d.join(format!("ranks-{n}.exr")));
        assert_eq!((film.frames, film.ranges.clone()), (40, vec![(0, 40)]), "{n} ranks");
        assert_eq!(film.samples_per_pixel(), one.samples_per_pixel());
        let (a, b) = (film.mean(), one.mean());
        let worst = a
            .iter()
            .zip(&b)
            .flat_map(|(p, q)| {
                (0..3).map(move |c| (p[c] - q[c]).abs() as f64 / p[c].abs().max(q[c].abs()).max(1e-3) as f64)
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-5, "{n} ranks differ from one process by {worst:.2e}");
    }
    std::fs::remove_dir_all(&d).ok();
}
