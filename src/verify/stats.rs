//! The statistics of `lightgraph verify`: two runs' images compared block by block and as a
//! whole, with standard errors from the spread of independent batches of frames.
//!
//! A run renders B batches of the same number of frames; each batch's block means are one
//! sample of the block's value. The spread of the B samples gives the standard error of the
//! block's mean (the method of batch means): right whatever the correlation between the pixels
//! of one frame, which light tracing, the BPTs and photon mapping have (a light sub-path or a
//! photon adds to many pixels). The batches of a progressive photon mapping run have shrinking
//! radii, so their means differ by more than noise; the spread then overstates the error, which
//! errs towards "not enough samples", never towards a false "differ".
//!
//! Two runs' difference in a block, over its standard error, is Welch's t (degrees of freedom
//! by Welch-Satterthwaite). Every block's three channels and the image mean's three channels
//! are one family of tests, corrected by Holm's method to a family-wise error of `alpha` over
//! the number of pairs the run tests: a run whose pairs all agree calls one of them "differ"
//! with probability at most `alpha`. The power says what the
//! test could have seen: the smallest relative difference it detects with probability `power`
//! in the image mean, and in each block; a pair that shows no difference is "agree" only when
//! that is small enough (`detect_mean`, and `detect_block` in the blocks that hold `coverage`
//! of the image's light), otherwise "not enough samples to tell".

use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// One run's per-block means, batch by batch.
#[derive(Debug, Clone)]
pub struct BlockBatches {
    /// Image width and height.
    pub size: (u32, u32),
    /// Block side in pixels (blocks at the right and bottom edges may be smaller).
    pub block: u32,
    /// Each batch's per-block mean radiance (blocks in rows, top first).
    pub batches: Vec<Vec<[f64; 3]>>,
    /// Each batch's image mean.
    pub image: Vec<[f64; 3]>,
}

impl BlockBatches {
    /// None yet, for images of `size` in blocks of `block` pixels.
    pub fn new(size: (u32, u32), block: u32) -> BlockBatches {
        BlockBatches {
            size,
            block,
            batches: Vec::new(),
            image: Vec::new(),
        }
    }

    /// Blocks across and down.
    pub fn grid(&self) -> (u32, u32) {
        (self.size.0.div_ceil(self.block), self.size.1.div_ceil(self.block))
    }

    /// Adds a batch: the per-pixel sums of `frames` frames' estimates (rows, top first).
    pub fn add(&mut self, sums: &[[f64; 3]], frames: u32) {
        let (w, h) = self.size;
        let (gx, gy) = self.grid();
        let mut blocks = vec![[0.0f64; 3]; (gx * gy) as usize];
        let mut pixels = vec![0u32; blocks.len()];
        let mut image = [0.0f64; 3];
        for y in 0..h {
            for x in 0..w {
                let p = sums[(y * w + x) as usize];
                let b = ((y / self.block) * gx + x / self.block) as usize;
                pixels[b] += 1;
                for c in 0..3 {
                    blocks[b][c] += p[c];
                    image[c] += p[c];
                }
            }
        }
        let f = frames.max(1) as f64;
        for (m, n) in blocks.iter_mut().zip(&pixels) {
            *m = m.map(|v| v / (f * *n as f64));
        }
        self.batches.push(blocks);
        self.image.push(image.map(|v| v / (f * (w * h) as f64)));
    }

    /// Per block, the mean over batches and the variance of that mean.
    pub fn blocks(&self) -> Vec<Estimate> {
        let n = self.batches.first().map_or(0, Vec::len);
        (0..n)
            .map(|b| Estimate::of(self.batches.iter().map(|batch| batch[b])))
            .collect()
    }

    /// The image mean and the variance of that mean.
    pub fn image(&self) -> Estimate {
        Estimate::of(self.image.iter().copied())
    }
}

/// One image's estimates: per block, and of the image mean.
#[derive(Debug, Clone)]
pub struct Estimates {
    /// Per block (rows of blocks, top first).
    pub blocks: Vec<Estimate>,
    /// The image mean.
    pub image: Estimate,
}

impl BlockBatches {
    /// The blocks' and the image mean's estimates.
    pub fn estimates(&self) -> Estimates {
        Estimates {
            blocks: self.blocks(),
            image: self.image(),
        }
    }
}

impl Estimates {
    /// The estimates of an image given per pixel, as its mean and the variance of that mean
    /// (another renderer's reference, say), each pixel's variance estimated with `dof` degrees
    /// of freedom (independent passes less one), in blocks of `block` pixels. Pixels must be
    /// independent (each pixel's samples its own, as in a path tracer with a box filter): a
    /// region's variance is then the sum of its pixels' over the pixel count squared, and its
    /// degrees of freedom Welch-Satterthwaite's.
    pub fn of_pixels(size: (u32, u32), block: u32, mean: &[[f64; 3]], variance: &[[f64; 3]], dof: f64) -> Estimates {
        let (w, h) = size;
        let (gx, gy) = (w.div_ceil(block), h.div_ceil(block));
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); (gx * gy) as usize];
        for y in 0..h {
            for x in 0..w {
                members[((y / block) * gx + x / block) as usize].push((y * w + x) as usize);
            }
        }
        let region = |pixels: &[usize]| {
            let n = pixels.len() as f64;
            let mut e = Estimate {
                mean: [0.0; 3],
                variance: [0.0; 3],
                batches: 0,
            };
            let mut least_dof = f64::INFINITY;
            for c in 0..3 {
                e.mean[c] = pixels.iter().map(|&i| mean[i][c]).sum::<f64>() / n;
                e.variance[c] = pixels.iter().map(|&i| variance[i][c]).sum::<f64>() / (n * n);
                let parts = pixels
                    .iter()
                    .map(|&i| (variance[i][c] / (n * n)).powi(2) / dof)
                    .sum::<f64>();
                if parts > 0.0 {
                    least_dof = least_dof.min(e.variance[c].powi(2) / parts);
                }
            }
            // The smallest channel's degrees of freedom, as the batches they stand for.
            e.batches = if least_dof.is_finite() {
                least_dof.round() as usize + 1
            } else {
                dof as usize + 1
            };
            e
        };
        let all: Vec<usize> = (0..(w * h) as usize).collect();
        Estimates {
            blocks: members.iter().map(|m| region(m)).collect(),
            image: region(&all),
        }
    }
}

/// A mean over batches, its variance (the squared standard error) and the batches it came from.
#[derive(Debug, Clone, Copy)]
pub struct Estimate {
    /// Mean per channel.
    pub mean: [f64; 3],
    /// Variance of the mean per channel.
    pub variance: [f64; 3],
    /// Batches (for a region of independent pixels, [`Estimates::of_pixels`], its degrees of
    /// freedom plus one).
    pub batches: usize,
}

impl Estimate {
    /// The mean and its variance over batch values.
    pub fn of(values: impl Iterator<Item = [f64; 3]> + Clone) -> Estimate {
        let n = values.clone().count();
        let mut mean = [0.0; 3];
        for v in values.clone() {
            (0..3).for_each(|c| mean[c] += v[c] / n as f64);
        }
        let mut variance = [0.0; 3];
        if n > 1 {
            for v in values {
                (0..3).for_each(|c| variance[c] += (v[c] - mean[c]).powi(2));
            }
            variance = variance.map(|s| s / ((n - 1) * n) as f64);
        }
        Estimate {
            mean,
            variance,
            batches: n,
        }
    }
}

impl Estimate {
    /// The light of the mean (its channels' sum) and that sum's relative standard error.
    pub fn light_and_error(&self) -> (f64, f64) {
        let l = light(self);
        (l, relative(self.variance.iter().sum::<f64>().sqrt(), l))
    }
}

impl TestSettings {
    /// The family-wise error of one pair's tests.
    pub fn pair_alpha(&self) -> f64 {
        self.alpha / self.pairs.max(1) as f64
    }
}

/// What the test of two runs may conclude.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// No difference, and the test could have seen one of the stated size.
    Agree,
    /// A difference beyond noise (Holm-corrected).
    Differ,
    /// No difference seen, but the test could not have seen one of the stated size.
    Undecided,
}

impl Verdict {
    /// The word reports use.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Agree => "agree",
            Verdict::Differ => "differ",
            Verdict::Undecided => "not enough samples to tell",
        }
    }
}

/// The settings of the test.
#[derive(Debug, Clone, Copy)]
pub struct TestSettings {
    /// Family-wise error rate of the run: the probability that any pair that agrees is called
    /// "differ" (each of its `pairs` pairs is tested at alpha / pairs).
    pub alpha: f64,
    /// The pairs the run tests.
    pub pairs: usize,
    /// Probability with which the test must detect a difference of the sizes below.
    pub power: f64,
    /// Relative difference of the image means the test must be able to see.
    pub detect_mean: f64,
    /// Relative difference of a block's mean the test must be able to see ...
    pub detect_block: f64,
    /// ... in the blocks holding this fraction of the image's light.
    pub coverage: f64,
    /// The bias a graph that declares some of its light biased at a finite budget (photon
    /// mapping's blur) may have in the image mean, relative to that light ([`Biased`]): the
    /// difference the test allows there on top of the noise.
    pub bias_tolerance_mean: f64,
    /// The same for a block's mean.
    pub bias_tolerance_block: f64,
}

impl Default for TestSettings {
    fn default() -> Self {
        TestSettings {
            alpha: 0.01,
            pairs: 1,
            power: 0.9,
            detect_mean: 0.01,
            detect_block: 0.1,
            coverage: 0.9,
            bias_tolerance_mean: 0.01,
            bias_tolerance_block: 0.1,
        }
    }
}

/// One block's comparison.
#[derive(Debug, Clone, Copy)]
pub struct BlockTest {
    /// Welch's t of the channel with the largest |t| (positive: the first run is brighter).
    pub t: f64,
    /// Whether a channel's difference beyond its bias allowance is significant after the
    /// correction.
    pub rejected: bool,
    /// The relative difference of the block's light, (a - b) / mean of both.
    pub difference: f64,
    /// The difference of the block's light the declared bias allows, relative as `difference`
    /// (0 in a pair held to the unbiased test).
    pub allowance: f64,
    /// The relative difference of the block's light the test detects with the stated power.
    pub detectable: f64,
    /// The block's light (sum of the channels' means, both runs averaged).
    pub light: f64,
}

/// The comparison of two runs.
#[derive(Debug, Clone)]
pub struct PairTest {
    /// The verdict.
    pub verdict: Verdict,
    /// Per block.
    pub blocks: Vec<BlockTest>,
    /// Tests in the family (3 per block with light or difference, 3 for the mean).
    pub tests: usize,
    /// The critical |t| of the strictest (first) Holm step at the median degrees of freedom.
    pub t_critical: f64,
    /// The image means' light (channel sums) of the two runs.
    pub light: (f64, f64),
    /// Relative difference of the image means' light, (a - b) / mean of both.
    pub mean_difference: f64,
    /// Welch's t of the image means (the channel with the largest |t|).
    pub mean_t: f64,
    /// Whether a channel of the image mean differs after the correction.
    pub mean_rejected: bool,
    /// The relative difference of the image mean the test detects with the stated power.
    pub mean_detectable: f64,
    /// The difference of the image means' light the declared bias allows, relative.
    pub mean_allowance: f64,
    /// The fraction of the image's light in blocks where the test detects `detect_block`.
    pub coverage: f64,
}

impl PairTest {
    /// Blocks whose difference is significant.
    pub fn blocks_rejected(&self) -> usize {
        self.blocks.iter().filter(|b| b.rejected).count()
    }

    /// The largest |t| of a block.
    pub fn max_block_t(&self) -> f64 {
        self.worst_block().map_or(0.0, |(_, b)| b.t.abs())
    }

    /// The block with the largest |t|, and its index.
    pub fn worst_block(&self) -> Option<(usize, &BlockTest)> {
        self.blocks
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.t.abs().total_cmp(&b.1.t.abs()))
    }
}

/// One Welch test: t, degrees of freedom and two-sided p-value.
#[derive(Debug, Clone, Copy)]
struct Welch {
    t: f64,
    dof: f64,
    p: f64,
    se: f64,
}

/// Welch's test of channel `c` of two estimates, of the null hypothesis that their expected
/// values differ by at most `allowance` (0: that they are equal): the difference is shrunk
/// towards 0 by the allowance before it is divided by its standard error, which keeps the
/// test's level for every difference within the allowance. `None` when the difference is
/// float rounding (`floor` and [`ROUNDING_RELATIVE`]: nothing to test).
fn welch(a: &Estimate, b: &Estimate, c: usize, floor: f64, allowance: f64) -> Option<Welch> {
    let raw = a.mean[c] - b.mean[c];
    let scale = a.mean[c].abs().max(b.mean[c].abs());
    if raw.abs() <= floor + ROUNDING_RELATIVE * scale {
        return None;
    }
    let d = raw.signum() * (raw.abs() - allowance).max(0.0);
    let (va, vb) = (a.variance[c], b.variance[c]);
    let s2 = va + vb;
    if s2.sqrt() <= ROUNDING_RELATIVE * scale {
        if d.abs() <= DETERMINISTIC_RELATIVE * scale {
            return None;
        }
        return Some(Welch {
            t: d.signum() * f64::INFINITY,
            dof: 1.0,
            p: 0.0,
            se: 0.0,
        });
    }
    let part = |v: f64, n: usize| if n > 1 { v * v / (n - 1) as f64 } else { 0.0 };
    let dof = (s2 * s2 / (part(va, a.batches) + part(vb, b.batches))).max(1.0);
    let t = d / s2.sqrt();
    let p = 2.0 * student(dof).sf(t.abs());
    Some(Welch {
        t,
        dof,
        p,
        se: s2.sqrt(),
    })
}

fn student(dof: f64) -> StudentsT {
    StudentsT::new(0.0, 1.0, dof.max(1.0)).expect("positive degrees of freedom")
}

/// Which of the p-values Holm's step-down method rejects at family-wise error `alpha`.
pub fn holm(p: &[f64], alpha: f64) -> Vec<bool> {
    let mut order: Vec<usize> = (0..p.len()).collect();
    order.sort_by(|&i, &j| p[i].total_cmp(&p[j]));
    let m = p.len();
    let mut rejected = vec![false; m];
    for (k, &i) in order.iter().enumerate() {
        if p[i] > alpha / (m - k) as f64 {
            break;
        }
        rejected[i] = true;
    }
    rejected
}

/// The relative difference a test of standard error `se` and `dof` degrees of freedom detects
/// with probability `power` at the per-test level `level` (two-sided), for a value `of`.
fn detectable(se: f64, dof: f64, level: f64, power: f64, of: f64) -> f64 {
    if of <= 0.0 {
        return f64::INFINITY;
    }
    let critical = student(dof).inverse_cdf(1.0 - level / 2.0);
    let z_power = Normal::new(0.0, 1.0).expect("unit normal").inverse_cdf(power);
    (critical + z_power) * se / of
}

/// The channel sum of a mean (the light a block holds, for weights and relative sizes).
fn light(e: &Estimate) -> f64 {
    e.mean.iter().map(|v| v.abs()).sum()
}

/// `part / of`, 0 when `of` is 0.
fn relative(part: f64, of: f64) -> f64 {
    if of > 0.0 { part / of } else { 0.0 }
}

/// Differences of a channel's mean below this fraction of the image's mean light, plus
/// [`ROUNDING_RELATIVE`] of the channel's own mean, are float rounding, not differences: black
/// blocks that two estimators fill with 1e-20 and 0, or a block that sees only a constant
/// background, which every batch of every estimator renders to the same value but for the last
/// bits (its variance then is 0 and any t infinite).
const ROUNDING: f64 = 1e-6;

/// See [`ROUNDING`].
const ROUNDING_RELATIVE: f64 = 1e-5;

/// Where both runs' standard errors are float rounding (a block that sees only a constant
/// background, every batch the same value), a relative difference below this is the estimators'
/// arithmetic, not a difference of what they estimate (measured on an H200: path tracing and
/// the BPTs 1e-4 apart on the background box's sky).
const DETERMINISTIC_RELATIVE: f64 = 1e-3;

/// The light of a run's estimate that its graph declares may be biased at a finite budget
/// (docs/verify.md, "Bias"): the test allows a difference of the settings' bias tolerance times
/// this light, per channel, on top of the statistical test.
#[derive(Debug, Clone, Default)]
pub enum Biased {
    /// None: the run is held to the unbiased test.
    #[default]
    None,
    /// All of it: the graph declares a biased class the scene has paths of and does not say
    /// how much light its biased technique adds.
    All,
    /// The light its biased technique added (its film's second channel), per block and in the
    /// image mean.
    Part(Estimates),
}

impl Biased {
    /// The biased light of channel `c` of region `k` (the image mean when `k` is the block
    /// count) of a run whose estimate there is `whole`.
    fn light(&self, k: usize, c: usize, whole: &Estimate) -> f64 {
        match self {
            Biased::None => 0.0,
            Biased::All => whole.mean[c].abs(),
            Biased::Part(part) if k == part.blocks.len() => part.image.mean[c].abs(),
            Biased::Part(part) => part.blocks[k].mean[c].abs(),
        }
    }
}

/// Compares two runs' blocks and image means; `bias`: what of each run's estimate its graph
/// declares may be biased ([`Biased`]).
pub fn compare(a: &BlockBatches, b: &BlockBatches, settings: &TestSettings, bias: [&Biased; 2]) -> PairTest {
    compare_estimates(&a.estimates(), &b.estimates(), settings, bias)
}

/// [`compare`] of two images' estimates (the same blocks of the same size).
pub fn compare_estimates(a: &Estimates, b: &Estimates, settings: &TestSettings, bias: [&Biased; 2]) -> PairTest {
    let (blocks_a, blocks_b) = (&a.blocks, &b.blocks);
    let (image_a, image_b) = (a.image, b.image);
    let pairs: Vec<(&Estimate, &Estimate)> = blocks_a
        .iter()
        .zip(blocks_b.iter())
        .chain(std::iter::once((&image_a, &image_b)))
        .collect();
    // Per region and channel, the difference the declared bias allows: the tolerance times
    // each run's biased light (the two may be biased in opposite directions).
    let allowances: Vec<[f64; 3]> = pairs
        .iter()
        .enumerate()
        .map(|(k, (x, y))| {
            let tolerance = match k + 1 == pairs.len() {
                true => settings.bias_tolerance_mean,
                false => settings.bias_tolerance_block,
            };
            [0, 1, 2].map(|c| tolerance * (bias[0].light(k, c, x) + bias[1].light(k, c, y)))
        })
        .collect();
    // The family: every channel with something to test, Holm-corrected together.
    let floor = ROUNDING * 0.5 * (light(&image_a) + light(&image_b));
    let tests: Vec<Vec<Option<Welch>>> = pairs
        .iter()
        .zip(&allowances)
        .map(|((x, y), allow)| (0..3).map(|c| welch(x, y, c, floor, allow[c])).collect())
        .collect();
    let p: Vec<f64> = tests.iter().flatten().flatten().map(|w| w.p).collect();
    let mut rejected = holm(&p, settings.pair_alpha()).into_iter();
    let m = p.len().max(1);
    let level = settings.pair_alpha() / m as f64;
    let mut results: Vec<BlockTest> = Vec::new();
    for ((&(x, y), channels), allow) in pairs.iter().zip(&tests).zip(&allowances) {
        // Every channel's verdict is taken (no short cut), so the next block starts at its own.
        let n = channels.iter().flatten().count();
        let found = (&mut rejected).take(n).fold(false, |any, r| any | r);
        let allowance = allow.iter().sum::<f64>();
        results.push(block_test((x, y), channels, found, allowance, (level, settings.power)));
    }
    let mean = results.pop().expect("the image mean's test");
    let coverage = coverage(&results, settings.detect_block);
    let differ = mean.rejected || results.iter().any(|b| b.rejected);
    let powerful = mean.detectable <= settings.detect_mean && coverage >= settings.coverage;
    let verdict = match (differ, powerful) {
        (true, _) => Verdict::Differ,
        (false, true) => Verdict::Agree,
        (false, false) => Verdict::Undecided,
    };
    PairTest {
        verdict,
        blocks: results,
        tests: m,
        t_critical: median_critical(&tests, level),
        light: (light(&image_a), light(&image_b)),
        mean_difference: mean.difference,
        mean_t: mean.t,
        mean_rejected: mean.rejected,
        mean_detectable: mean.detectable,
        mean_allowance: mean.allowance,
        coverage,
    }
}

/// One block's (or the mean's) summary from its channels' tests: the largest |t|, whether it
/// differs (`found` significant beyond the bias `allowance`, the channels' sum), and what it
/// could have detected at the per-test `level` with `power`.
fn block_test(
    (x, y): (&Estimate, &Estimate),
    channels: &[Option<Welch>],
    found: bool,
    allowance: f64,
    (level, power): (f64, f64),
) -> BlockTest {
    let tested: Vec<&Welch> = channels.iter().flatten().collect();
    let t = tested
        .iter()
        .map(|w| w.t)
        .fold(0.0, |m: f64, t| if t.abs() > m.abs() { t } else { m });
    let se = tested.iter().map(|w| w.se * w.se).sum::<f64>().sqrt();
    let dof = tested.iter().map(|w| w.dof).fold(f64::INFINITY, f64::min);
    let of = 0.5 * (light(x) + light(y));
    let detectable = match tested.is_empty() {
        true => f64::INFINITY,
        false => detectable(se, dof, level, power, of),
    };
    BlockTest {
        t,
        rejected: found,
        difference: relative(light(x) - light(y), of),
        allowance: relative(allowance, of),
        detectable,
        light: of,
    }
}

/// The fraction of the blocks' light in blocks whose detectable difference is at most
/// `detect`.
fn coverage(blocks: &[BlockTest], detect: f64) -> f64 {
    let total = blocks.iter().fold(0.0, |s, b| s + b.light);
    let covered = blocks
        .iter()
        .filter(|b| b.detectable <= detect)
        .fold(0.0, |s, b| s + b.light);
    relative(covered, total)
}

/// The critical |t| at the per-test `level` for the median degrees of freedom of the tests.
fn median_critical(tests: &[Vec<Option<Welch>>], level: f64) -> f64 {
    let mut dofs: Vec<f64> = tests.iter().flatten().flatten().map(|w| w.dof).collect();
    dofs.sort_by(f64::total_cmp);
    dofs.get(dofs.len() / 2)
        .map_or(f64::INFINITY, |&d| student(d).inverse_cdf(1.0 - level / 2.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of `batches` batches over a 4x4 image in 2x2 blocks: each pixel `value(x, y)` plus
    /// noise of size `noise` from a fixed sequence.
    fn run(batches: u32, noise: f64, seed: u64, value: impl Fn(u32, u32) -> f64) -> BlockBatches {
        let mut r = BlockBatches::new((4, 4), 2);
        let mut state = seed.wrapping_mul(0x9e3779b97f4a7c15) | 1;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..batches {
            let sums: Vec<[f64; 3]> = (0..16)
                .map(|i| {
                    let v = value(i % 4, i / 4);
                    [0, 1, 2].map(|_| 10.0 * (v + noise * uniform()))
                })
                .collect();
            r.add(&sums, 10);
        }
        r
    }

    #[test]
    fn independent_pixels_give_region_means_variances_and_degrees_of_freedom() {
        // 4x4 pixels in 2x2 blocks, each pixel's variance of the mean v (estimated from 16
        // passes, 15 degrees of freedom): a block's variance is 4 v / 16, its degrees of
        // freedom (4 v / 16)^2 / (4 (v / 16)^2 / 15) = 60; the image's 16 v / 256 and 240.
        let mean: Vec<[f64; 3]> = (0..16).map(|i| [i as f64; 3]).collect();
        let variance = vec![[0.5; 3]; 16];
        let e = Estimates::of_pixels((4, 4), 2, &mean, &variance, 15.0);
        assert_eq!(e.blocks.len(), 4);
        assert_eq!(e.blocks[0].mean, [2.5; 3], "pixels 0, 1, 4, 5");
        assert_eq!(e.blocks[0].variance, [0.125; 3]);
        assert_eq!(e.blocks[0].batches, 61);
        assert_eq!(
            (e.image.mean, e.image.variance, e.image.batches),
            ([7.5; 3], [0.5 / 16.0; 3], 241)
        );
        // Against itself: nothing to tell apart.
        let t = compare_estimates(&e, &e, &TestSettings::default(), [&Biased::None; 2]);
        assert_eq!(t.blocks_rejected(), 0);
        assert!(!t.mean_rejected);
    }

    #[test]
    fn batches_give_block_means_and_their_spread() {
        let r = run(8, 0.0, 1, |x, y| if x < 2 && y < 2 { 2.0 } else { 1.0 });
        let blocks = r.blocks();
        assert_eq!(blocks.len(), 4);
        assert_eq!(blocks[0].mean, [2.0; 3]);
        assert_eq!(blocks[3].mean, [1.0; 3]);
        assert_eq!(blocks[0].variance, [0.0; 3]);
        assert!((r.image().mean[0] - 1.25).abs() < 1e-12);
    }

    #[test]
    fn holm_steps_down() {
        // m = 4, alpha 0.04: thresholds 0.01, 0.0133, 0.02, 0.04.
        assert_eq!(holm(&[0.005, 0.012, 0.5, 0.019], 0.04), vec![true, true, false, true]);
        assert_eq!(holm(&[0.02, 0.012], 0.02), vec![false, false]);
    }

    #[test]
    fn equal_runs_agree_and_different_ones_differ() {
        let settings = TestSettings {
            detect_mean: 0.05,
            detect_block: 0.2,
            ..TestSettings::default()
        };
        let a = run(32, 0.2, 1, |_, _| 1.0);
        let b = run(32, 0.2, 2, |_, _| 1.0);
        assert_eq!(compare(&a, &b, &settings, [&Biased::None; 2]).verdict, Verdict::Agree);
        // One block 30% darker: its test rejects, the others do not.
        let c = run(32, 0.2, 3, |x, y| if x >= 2 && y >= 2 { 0.7 } else { 1.0 });
        let t = compare(&a, &c, &settings, [&Biased::None; 2]);
        assert_eq!(t.verdict, Verdict::Differ);
        assert_eq!(
            t.blocks.iter().map(|b| b.rejected).collect::<Vec<_>>(),
            [false, false, false, true]
        );
    }

    #[test]
    fn too_few_samples_are_not_agreement() {
        // Noise as large as the signal, 4 batches: nothing is seen, and nothing could be.
        let a = run(4, 1.0, 1, |_, _| 1.0);
        let b = run(4, 1.0, 2, |_, _| 0.9);
        assert_eq!(
            compare(&a, &b, &TestSettings::default(), [&Biased::None; 2]).verdict,
            Verdict::Undecided
        );
    }

    /// An image mean (a 2 x 2 grid of equal blocks and their mean) of `value` per channel with
    /// standard error `se`, from 64 batches.
    fn uniform(value: f64, se: f64) -> Estimates {
        let e = Estimate {
            mean: [value; 3],
            variance: [se * se; 3],
            batches: 64,
        };
        Estimates {
            blocks: vec![e; 4],
            image: e,
        }
    }

    #[test]
    fn a_bias_declared_for_a_part_of_the_light_excuses_only_that_part() {
        // An estimator whose biased technique adds 2.4% of the image (a caustic photon map
        // beside path tracing), 0.5% brighter than an unbiased one everywhere: a split error.
        // The noise (0.05% of the value a run) lets the test see 0.5% and decide.
        let unbiased = uniform(1.0, 0.0005);
        let wrong = uniform(1.005, 0.0005);
        let settings = TestSettings::default();
        let all_or_nothing = compare_estimates(&unbiased, &wrong, &settings, [&Biased::None, &Biased::All]);
        // The whole image declared biased: 1% of it allowed, the error excused.
        assert_eq!(all_or_nothing.verdict, Verdict::Agree);
        assert!((all_or_nothing.mean_allowance - 0.01).abs() < 1e-4);
        // Only the caustic's 2.4% declared biased: 1% of that (0.024%) allowed, the error seen.
        let caustic = Biased::Part(uniform(0.024, 0.0001));
        let per_class = compare_estimates(&unbiased, &wrong, &settings, [&Biased::None, &caustic]);
        assert_eq!(per_class.verdict, Verdict::Differ);
        assert!(per_class.mean_rejected);
        assert!((per_class.mean_allowance - 0.00024).abs() < 1e-5);
        // A difference within the allowance is excused: 0.02%, which the unbiased test sees
        // at this noise (t 14).
        let (exact, close) = (uniform(1.0, 0.00001), uniform(1.0002, 0.00001));
        let strict = compare_estimates(&exact, &close, &settings, [&Biased::None; 2]);
        assert_eq!(strict.verdict, Verdict::Differ);
        let within = compare_estimates(&exact, &close, &settings, [&Biased::None, &caustic]);
        assert_eq!(within.verdict, Verdict::Agree);
    }
}
