//! Statistics of a stress render: every frame's image kept apart, so the standard error of a
//! region's mean comes from the spread of its per-frame means (right even for estimators whose
//! samples touch many pixels, such as light tracing, where pixels are correlated).

/// Student-t threshold of the statistical checks. With at least [`MIN_FRAMES`] frames, a
/// |t| above 6 has a probability of about 1.2e-6 (t with 31 degrees of freedom) when the
/// invariant holds; a stress run makes fewer than 1000 such tests, so a correct renderer
/// fails one by chance less than once in 800 runs.
pub const Z_LIMIT: f64 = 6.0;

/// Fewest frames a statistical check accepts.
pub const MIN_FRAMES: usize = 32;

/// Per-frame images of one render.
#[derive(Debug, Clone)]
pub struct Frames {
    /// Width and height.
    pub size: (u32, u32),
    /// Each frame's estimate per pixel.
    pub frames: Vec<Vec<[f32; 3]>>,
}

/// A region's mean over frames and its standard error, per channel.
#[derive(Debug, Clone, Copy)]
pub struct RegionStat {
    /// Mean of the region's pixels over all frames.
    pub mean: [f64; 3],
    /// Standard error of that mean, from the spread of the per-frame region means.
    pub se: [f64; 3],
}

impl Frames {
    /// The mean image.
    pub fn mean(&self) -> Vec<[f64; 3]> {
        let n = self.frames.len().max(1) as f64;
        let mut m = vec![[0.0f64; 3]; (self.size.0 * self.size.1) as usize];
        for f in &self.frames {
            for (acc, p) in m.iter_mut().zip(f) {
                for c in 0..3 {
                    acc[c] += p[c] as f64 / n;
                }
            }
        }
        m
    }

    /// Mean and standard error over the pixels where `weight` is non-zero, weighted.
    pub fn region(&self, weight: &[f64]) -> RegionStat {
        let total: f64 = weight.iter().sum();
        let per_frame: Vec<[f64; 3]> = self
            .frames
            .iter()
            .map(|f| {
                let mut s = [0.0; 3];
                for (p, w) in f.iter().zip(weight).filter(|(_, w)| **w != 0.0) {
                    for c in 0..3 {
                        s[c] += p[c] as f64 * w / total;
                    }
                }
                s
            })
            .collect();
        let n = per_frame.len() as f64;
        let mut stat = RegionStat {
            mean: [0.0; 3],
            se: [0.0; 3],
        };
        for c in 0..3 {
            let m = per_frame.iter().map(|s| s[c]).sum::<f64>() / n;
            let var = per_frame.iter().map(|s| (s[c] - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
            stat.mean[c] = m;
            stat.se[c] = (var / n).sqrt();
        }
        stat
    }

    /// The image cut into about `blocks` × `blocks` rectangles: one weight image per
    /// rectangle, with `mask` (per pixel) applied; empty rectangles are left out.
    pub fn blocks(&self, blocks: u32, mask: &[bool]) -> Vec<Vec<f64>> {
        let (w, h) = self.size;
        let (bw, bh) = (w.div_ceil(blocks), h.div_ceil(blocks));
        let mut out = Vec::new();
        for by in 0..h.div_ceil(bh) {
            for bx in 0..w.div_ceil(bw) {
                let weight: Vec<f64> = (0..w * h)
                    .map(|i| {
                        let (x, y) = (i % w, i / w);
                        let inside = x / bw == bx && y / bh == by && mask[i as usize];
                        if inside { 1.0 } else { 0.0 }
                    })
                    .collect();
                if weight.iter().any(|&v| v > 0.0) {
                    out.push(weight);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_standard_error_comes_from_the_frames() {
        // Two pixels whose values are perfectly anti-correlated: the region mean never moves,
        // although each pixel does.
        let frames = Frames {
            size: (2, 1),
            frames: (0..8)
                .map(|i| {
                    let a = if i % 2 == 0 { 1.0 } else { 3.0 };
                    vec![[a; 3], [4.0 - a; 3]]
                })
                .collect(),
        };
        let both = frames.region(&[1.0, 1.0]);
        assert_eq!((both.mean[0], both.se[0]), (2.0, 0.0));
        let left = frames.region(&[1.0, 0.0]);
        assert_eq!(left.mean[1], 2.0);
        // Sample variance of alternating 1 and 3 over 8 frames is 8/7; of the mean, 1/7.
        assert!((left.se[2] - (1.0f64 / 7.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn blocks_cover_the_masked_pixels_once() {
        let frames = Frames {
            size: (5, 3),
            frames: vec![vec![[0.0; 3]; 15]],
        };
        let mut mask = vec![true; 15];
        mask[0] = false;
        let blocks = frames.blocks(2, &mask);
        assert_eq!(blocks.len(), 4);
        let covered: Vec<f64> = (0..15).map(|i| blocks.iter().map(|b| b[i]).sum()).collect();
        assert_eq!(covered[0], 0.0);
        assert!(covered[1..].iter().all(|&c| c == 1.0));
    }
}
