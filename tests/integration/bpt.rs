//! Light tracing and bidirectional path tracing against path tracing: per-region means with
//! standard errors from each render's own per-frame estimates (frames are independent, so
//! the spread of the frame estimates of a region gives the variance of its mean; pixels are
//! not, as light sub-paths splat into many). Two estimators that both sample every path of a
//! region agree within 4 combined standard errors: with 48 frames the
//! standard errors have 47 degrees of freedom, so |t| > 4 happens about once in 4000 per
//! block and channel, about 1% for a test of 16 blocks x 3 channels. Where one estimator
//! cannot sample some paths (a structural gap), the difference is shown to be far larger.

/// Frames per render: independent estimates for the standard errors.
const FRAMES: u32 = 48;

use crate::common::{assert_finite, gpu, render};
use lightgraph::render::{Image, LoadedScene, Session, SessionOptions, load_graph, load_scene};
use lightgraph_engine::ConstValue;

/// Per-frame block means of a render: `frames` frames of `spp` samples per pixel on a `size`
/// x `size` image, averaged over `n` x `n` blocks. Frame k's estimate is recovered from the
/// running means as k m_k - (k - 1) m_(k-1). Light tracing splats one sub-path into many
/// pixels, so pixels are not independent within a frame; frames are, so the spread of the
/// per-frame block means gives the standard error.
struct Frames {
    /// [frame][block][channel]
    means: Vec<Vec<[f64; 3]>>,
}

#[allow(clippy::too_many_arguments)]
fn render_frames(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    size: u32,
    spp: u32,
    frames: u32,
    seed: u32,
    n: u32,
) -> Frames {
    let graph = load_graph(graph).unwrap();
    let options = SessionOptions {
        width: size,
        height: size,
        samples_per_frame: spp,
        seed,
        constants: Default::default(),
        layout: Default::default(),
    };
    let mut session = Session::new(gpu(), &graph, layout, scene, options).unwrap();
    let mut previous = vec![[0f64; 3]; (n * n) as usize];
    let mut means = Vec::new();
    for k in 1..=frames {
        session.render_frame().unwrap();
        let image = session.image().unwrap();
        assert_finite(&image, &format!("{}:{layout}", graph.name));
        let current = block_means(&image, n);
        let frame: Vec<[f64; 3]> = current
            .iter()
            .zip(&previous)
            .map(|(c, p)| std::array::from_fn(|i| k as f64 * c[i] - (k - 1) as f64 * p[i]))
            .collect();
        means.push(frame);
        previous = current;
    }
    Frames { means }
}

/// Mean radiance per block of an image.
fn block_means(image: &Image, n: u32) -> Vec<[f64; 3]> {
    let (bw, bh) = (image.width / n, image.height / n);
    let mut sums = vec![[0f64; 3]; (n * n) as usize];
    for y in 0..image.height {
        for x in 0..image.width {
            let b = ((y / bh) * n + x / bw) as usize;
            let pixel = image.mean[(y * image.width + x) as usize];
            for (sum, v) in sums[b].iter_mut().zip(pixel) {
                *sum += v as f64;
            }
        }
    }
    let area = (bw * bh) as f64;
    sums.iter().map(|s| s.map(|v| v / area)).collect()
}

impl Frames {
    /// Mean and standard error of block `b`, channel `c`, over the frames.
    fn stat(&self, b: usize, c: usize) -> (f64, f64) {
        let k = self.means.len() as f64;
        let mean = self.means.iter().map(|f| f[b][c]).sum::<f64>() / k;
        let var = self.means.iter().map(|f| (f[b][c] - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    }
}

/// The blocks in which the camera sees a light directly (path tracing with paths of one
/// segment: only directly visible emission is nonzero); light tracing cannot render those.
fn direct_light_blocks(scene: &LoadedScene, size: u32, n: u32) -> Vec<bool> {
    let direct = render(
        scene,
        "pt",
        "NaivePTsk",
        (size, size),
        1,
        1,
        1,
        &[("MAX_PATH_LENGTH", ConstValue::U32(1))],
    );
    block_means(&direct.image, n)
        .iter()
        .map(|m| m.iter().any(|v| *v > 0.0))
        .collect()
}

/// Largest |difference| / combined standard error over the blocks `keep` selects. Checks
/// that the comparison has power: every kept block's combined standard error is under
/// `max_rel_se` of its mean.
fn worst_z(a: &Frames, b: &Frames, keep: &[bool], max_rel_se: f64, what: &str) -> f64 {
    let mut worst = 0f64;
    for (i, kept) in keep.iter().enumerate() {
        if !kept {
            continue;
        }
        for c in 0..3 {
            let ((ma, sa), (mb, sb)) = (a.stat(i, c), b.stat(i, c));
            let se = (sa * sa + sb * sb).sqrt();
            let z = (ma - mb).abs() / se;
            eprintln!("{what} block {i} channel {c}: {ma:.5} vs {mb:.5} +- {se:.5} (z {z:.2})");
            assert!(
                se < max_rel_se * ma.max(mb),
                "{what} block {i}: standard error {se} too large to test {ma} vs {mb}"
            );
            worst = worst.max(z);
        }
    }
    worst
}

#[test]
fn light_tracing_agrees_with_path_tracing_on_the_diffuse_box() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let (size, n) = (32, 4);
    let pt = render_frames(&scene, "pt", "NaivePTsk", size, 2, FRAMES, 7, n);
    let lt = render_frames(&scene, "lt", "LTsk", size, 2, FRAMES, 8, n);
    let keep: Vec<bool> = direct_light_blocks(&scene, size, n).iter().map(|d| !d).collect();
    let z = worst_z(&lt, &pt, &keep, 0.05, "lt vs pt");
    assert!(
        z < 4.0,
        "light tracing differs from path tracing by {z:.2} standard errors"
    );
}
