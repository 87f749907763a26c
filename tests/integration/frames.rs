//! Per-frame statistics of renders: block means of each frame's own estimate, whose spread
//! over independent frames gives the standard error of a block's mean (pixels are not
//! independent within a frame when light sub-paths splat or photons are shared; frames are).

use crate::common::{assert_finite, gpu};
use lightgraph::run::{Image, LoadedScene, Session, SessionOptions, load_graph};
use lightgraph_engine::ConstValue;

/// Per-frame block means of a render: `frames` frames of `spp` samples per pixel on a `size`
/// x `size` image, averaged over `n` x `n` blocks. Frame k's estimate is recovered from the
/// running means as k m_k - (k - 1) m_(k-1). Light tracing splats one sub-path into many
/// pixels, so pixels are not independent within a frame; frames are, so the spread of the
/// per-frame block means gives the standard error.
pub struct Frames {
    /// [frame][block][channel]
    pub means: Vec<Vec<[f64; 3]>>,
}

#[allow(clippy::too_many_arguments)]
pub fn render_frames(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    size: u32,
    spp: u32,
    frames: u32,
    seed: u32,
    n: u32,
) -> Frames {
    render_frames_with(scene, graph, layout, (size, spp, frames, seed, n), &[])
}

/// [`render_frames`] with constant overrides; `run` is (size, spp, frames, seed, n).
pub fn render_frames_with(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    run: (u32, u32, u32, u32, u32),
    constants: &[(&str, ConstValue)],
) -> Frames {
    let (size, spp, frames, seed, n) = run;
    let graph = load_graph(graph).unwrap();
    let options = SessionOptions {
        width: size,
        height: size,
        samples_per_frame: spp,
        seed,
        constants: constants.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
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
pub fn block_means(image: &Image, n: u32) -> Vec<[f64; 3]> {
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
    pub fn stat(&self, b: usize, c: usize) -> (f64, f64) {
        let k = self.means.len() as f64;
        let mean = self.means.iter().map(|f| f[b][c]).sum::<f64>() / k;
        let var = self.means.iter().map(|f| (f[b][c] - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    }
}

/// Largest |difference| / combined standard error over the blocks `keep` selects. Checks
/// that the comparison has power: every kept block's combined standard error is under
/// `max_rel_se` of its mean, except in blocks `noisy` marks (where the camera sees a light
/// edge, whose pixel-jitter noise both estimators share).
pub fn worst_z(a: &Frames, b: &Frames, keep: &[bool], noisy: &[bool], max_rel_se: f64, what: &str) -> f64 {
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
                noisy[i] || se < max_rel_se * ma.max(mb),
                "{what} block {i}: standard error {se} too large to test {ma} vs {mb}"
            );
            worst = worst.max(z);
        }
    }
    worst
}
