//! Chi-square goodness-of-fit tests of direction samplers against their pdfs, as Mitsuba 3
//! and pbrt-v4 test theirs. Directions are binned over the sphere (or a cap of it around an
//! axis, to resolve narrow lobes) in (cos θ, φ), where equal steps are equal solid angles.
//! Expected counts come from the pdf integrated over each bin by the midpoint rule on a
//! sub-grid; bins expecting fewer than 5 samples are pooled; Pearson's statistic gives a
//! p-value from the chi-square distribution. Discrete (delta) samples are cells of their own,
//! expected in proportion to their probabilities.
//!
//! Samples are `vec4`s: `w = 0` no sample (lost), `w = 1` a direction `xyz` from a
//! continuous lobe, `w = 2 + k` a direction from discrete outcome `k`.

/// Pooling threshold: cells expected to hold fewer samples are merged (Pearson's statistic
/// is only chi-square distributed when every cell expects at least about 5).
const MIN_EXPECTED: f64 = 5.0;

/// A grid over a spherical cap around `axis` (the whole sphere when `cos_min` = -1): `cos_bins`
/// equal steps of cos θ from `cos_min` to 1 times `phi_bins` equal steps of φ.
#[derive(Debug, Clone)]
pub struct SphereBins {
    frame: [[f64; 3]; 3],
    cos_min: f64,
    cos_bins: usize,
    phi_bins: usize,
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl SphereBins {
    /// The whole sphere, around +z.
    pub fn sphere(cos_bins: usize, phi_bins: usize) -> Self {
        Self::cap([0.0, 0.0, 1.0], -1.0, cos_bins, phi_bins)
    }

    /// The cap of directions within angle acos(`cos_min`) of `axis`.
    pub fn cap(axis: [f64; 3], cos_min: f64, cos_bins: usize, phi_bins: usize) -> Self {
        let n = normalize(axis);
        let helper = if n[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let t = normalize(cross(helper, n));
        let b = cross(n, t);
        SphereBins {
            frame: [t, b, n],
            cos_min,
            cos_bins,
            phi_bins,
        }
    }

    /// Whether the grid covers the whole sphere.
    pub fn is_sphere(&self) -> bool {
        self.cos_min <= -1.0
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.cos_bins * self.phi_bins
    }

    /// The bin of direction `d` (need not be unit length), if it lies in the cap.
    pub fn bin_of(&self, d: [f64; 3]) -> Option<usize> {
        let d = normalize(d);
        let [t, b, n] = self.frame;
        let c = dot(d, n).clamp(-1.0, 1.0);
        if c < self.cos_min {
            return None;
        }
        let phi = dot(d, b).atan2(dot(d, t)).rem_euclid(std::f64::consts::TAU);
        let i = (((c - self.cos_min) / (1.0 - self.cos_min)) * self.cos_bins as f64) as usize;
        let j = (phi / std::f64::consts::TAU * self.phi_bins as f64) as usize;
        Some(i.min(self.cos_bins - 1) * self.phi_bins + j.min(self.phi_bins - 1))
    }

    /// The midpoints of a `sub` × `sub` grid in every bin (bin after bin), as unit
    /// directions; each stands for [`Self::point_solid_angle`] steradians.
    pub fn quadrature_points(&self, sub: usize) -> Vec<[f32; 4]> {
        let [t, b, n] = self.frame;
        let mut out = Vec::with_capacity(self.len() * sub * sub);
        let dc = (1.0 - self.cos_min) / (self.cos_bins * sub) as f64;
        let dphi = std::f64::consts::TAU / (self.phi_bins * sub) as f64;
        for i in 0..self.cos_bins {
            for j in 0..self.phi_bins {
                for a in 0..sub {
                    for k in 0..sub {
                        let c = self.cos_min + ((i * sub + a) as f64 + 0.5) * dc;
                        let phi = ((j * sub + k) as f64 + 0.5) * dphi;
                        let s = (1.0 - c * c).max(0.0).sqrt();
                        let (x, y) = (s * phi.cos(), s * phi.sin());
                        let d: [f64; 3] = std::array::from_fn(|r| x * t[r] + y * b[r] + c * n[r]);
                        out.push([d[0] as f32, d[1] as f32, d[2] as f32, 0.0]);
                    }
                }
            }
        }
        out
    }

    /// The solid angle one quadrature point of a `sub` grid stands for.
    pub fn point_solid_angle(&self, sub: usize) -> f64 {
        (1.0 - self.cos_min) * std::f64::consts::TAU / (self.len() * sub * sub) as f64
    }

    /// The pdf integrated over each bin, from its values at [`Self::quadrature_points`].
    pub fn integrate(&self, pdf: &[f32], sub: usize) -> Vec<f64> {
        assert_eq!(pdf.len(), self.len() * sub * sub, "one pdf value per quadrature point");
        let w = self.point_solid_angle(sub);
        pdf.chunks(sub * sub)
            .map(|c| c.iter().map(|&p| p as f64).sum::<f64>() * w)
            .collect()
    }
}

/// Samples sorted into the bins, the discrete outcomes, the cells outside the grid and the
/// lost samples.
#[derive(Debug, Clone)]
pub struct Histogram {
    /// Continuous samples per bin.
    pub bins: Vec<f64>,
    /// Samples per discrete outcome.
    pub discrete: Vec<f64>,
    /// Continuous samples outside a cap.
    pub outside: f64,
    /// Samples with `w = 0`.
    pub lost: f64,
    /// All samples.
    pub total: f64,
}

/// Sorts `samples` into `grid`'s bins and `discrete_outcomes` discrete cells.
pub fn histogram(grid: &SphereBins, samples: &[[f32; 4]], discrete_outcomes: usize) -> Histogram {
    let mut h = Histogram {
        bins: vec![0.0; grid.len()],
        discrete: vec![0.0; discrete_outcomes],
        outside: 0.0,
        lost: 0.0,
        total: samples.len() as f64,
    };
    for s in samples {
        let tag = s[3].round() as i64;
        match tag {
            0 => h.lost += 1.0,
            1 => match grid.bin_of([s[0] as f64, s[1] as f64, s[2] as f64]) {
                Some(b) => h.bins[b] += 1.0,
                None => h.outside += 1.0,
            },
            k => {
                let k = (k - 2) as usize;
                assert!(k < discrete_outcomes, "discrete outcome {k} of {discrete_outcomes}");
                h.discrete[k] += 1.0;
            }
        }
    }
    h
}

/// The result of a test.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Pearson's statistic.
    pub statistic: f64,
    /// Degrees of freedom (cells after pooling, minus one).
    pub dof: usize,
    /// Probability of a statistic at least this large if the sampler matches the pdf.
    pub p_value: f64,
    /// Integral of the continuous pdf over the grid.
    pub pdf_integral: f64,
    /// Why the test failed outright (samples where the pdf is zero), if it did.
    pub failure: Option<String>,
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "chi2 = {:.1} with {} dof, p = {:.3e}, pdf integral {:.5}",
            self.statistic, self.dof, self.p_value, self.pdf_integral
        )?;
        if let Some(why) = &self.failure {
            write!(f, " ({why})")?;
        }
        Ok(())
    }
}

impl Outcome {
    /// Whether the test passes at significance `alpha`.
    pub fn passes(&self, alpha: f64) -> bool {
        self.failure.is_none() && self.p_value > alpha
    }
}

/// Most samples, as a fraction of all, that may fall in cells where the quadrature of the
/// pdf is 0: a lobe whose support ends inside a bin (rough refraction's, with GGX's long
/// tails) puts samples where no quadrature point sees the pdf (a few in 10^4 at 200k
/// samples, 24 x 48 bins); a sampler that puts more there is wrong. Whether the pdf is
/// positive at each sample's own direction is for the caller to check exactly.
const MAX_UNSUPPORTED: f64 = 1e-3;

/// Pearson's test of observed against expected cell counts, pooling cells that expect fewer
/// than [`MIN_EXPECTED`] (cells expecting nothing included). More than [`MAX_UNSUPPORTED`]
/// of the samples in cells expecting nothing fails the test.
pub fn pearson(observed: &[f64], expected: &[f64]) -> (f64, usize, f64, Option<String>) {
    assert_eq!(observed.len(), expected.len());
    let mut cells: Vec<(f64, f64)> = observed.iter().copied().zip(expected.iter().copied()).collect();
    let total: f64 = observed.iter().sum();
    let unsupported: f64 = cells.iter().filter(|(_, e)| *e <= 0.0).map(|(o, _)| o).sum();
    if unsupported > MAX_UNSUPPORTED * total {
        let failure = format!("{unsupported} samples fall where the pdf integrates to 0");
        return (f64::INFINITY, 0, 0.0, Some(failure));
    }
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut pooled: Vec<(f64, f64)> = Vec::new();
    let mut pool = (0.0, 0.0);
    for (o, e) in cells {
        if pool.1 < MIN_EXPECTED {
            pool.0 += o;
            pool.1 += e;
        } else {
            pooled.push((o, e));
        }
    }
    if pool.1 >= MIN_EXPECTED {
        pooled.push(pool);
    } else if let Some(last) = pooled.last_mut() {
        // Too little left to stand alone: fold it into the smallest cell that does.
        last.0 += pool.0;
        last.1 += pool.1;
    }
    if pooled.len() < 2 {
        return (0.0, 0, 1.0, None);
    }
    let statistic: f64 = pooled.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = pooled.len() - 1;
    (statistic, dof, chi2_survival(statistic, dof as f64), None)
}

/// Tests `samples` against the continuous pdf, whose values at `grid`'s quadrature points
/// (`sub` × `sub` per bin) are `pdf`, and the probabilities of the discrete outcomes.
/// On the whole sphere every sample is compared with the density it was drawn from; on a
/// cap, the test is conditional on the samples that fall in it (their distribution within
/// the cap must follow the pdf's; how many fall in it is not tested).
pub fn goodness_of_fit(grid: &SphereBins, samples: &[[f32; 4]], pdf: &[f32], sub: usize, discrete: &[f64]) -> Outcome {
    let h = histogram(grid, samples, discrete.len());
    let mass = grid.integrate(pdf, sub);
    let pdf_integral: f64 = mass.iter().sum();
    let (observed, expected): (Vec<f64>, Vec<f64>) = if grid.is_sphere() {
        let obs = h.bins.iter().chain(&h.discrete).copied().collect();
        let exp = mass.iter().chain(discrete).map(|p| p * h.total).collect();
        (obs, exp)
    } else {
        assert!(discrete.is_empty(), "a cap test has no discrete outcomes");
        let in_cap: f64 = h.bins.iter().sum();
        (h.bins.clone(), mass.iter().map(|p| p / pdf_integral * in_cap).collect())
    };
    let (statistic, dof, p_value, failure) = pearson(&observed, &expected);
    Outcome {
        statistic,
        dof,
        p_value,
        pdf_integral,
        failure,
    }
}

/// Significance of each of `tests` tests in a file such that all pass together with
/// probability 0.99 when every sampler is right (Šidák's correction, as Mitsuba 3's chi2
/// tests use).
pub fn significance(tests: u32) -> f64 {
    1.0 - 0.99f64.powf(1.0 / tests as f64)
}

/// P(X > x) for X chi-square distributed with `k` degrees of freedom: the regularised upper
/// incomplete gamma function Q(k/2, x/2).
pub fn chi2_survival(x: f64, k: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * k, 0.5 * x)
}

/// ln Γ(a) for a > 0: Stirling's series with the argument shifted above 10 by the recurrence
/// Γ(a) = Γ(a + 1) / a (error below 1e-13).
fn ln_gamma(a: f64) -> f64 {
    let mut a = a;
    let mut shift = 0.0;
    while a < 10.0 {
        shift -= a.ln();
        a += 1.0;
    }
    let inv = 1.0 / a;
    let inv2 = inv * inv;
    let series =
        inv * (1.0 / 12.0 - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 / 1188.0))));
    shift + (a - 0.5) * a.ln() - a + 0.5 * std::f64::consts::TAU.ln() + series
}

/// Q(a, x) = Γ(a, x) / Γ(a): for x < a + 1 from the power series of the lower function,
/// P(a, x) = x^a e^-x / Γ(a + 1) Σ x^n / ((a + 1) ... (a + n)); otherwise from the continued
/// fraction Γ(a, x) = x^a e^-x / (x + 1 - a - 1 (1 - a) / (x + 3 - a - ...)), evaluated by
/// the modified Lentz method.
fn gamma_q(a: f64, x: f64) -> f64 {
    let prefix = (a * x.ln() - x - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut n = 1.0;
        while term > sum * 1e-15 && n < 1e5 {
            term *= x / (a + n);
            sum += term;
            n += 1.0;
        }
        (1.0 - prefix * sum).max(0.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut f = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            f *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        prefix * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_survival_matches_known_values() {
        // Two degrees of freedom: exactly exp(-x / 2).
        for x in [0.1, 1.0, 5.0, 20.0, 80.0] {
            let q = chi2_survival(x, 2.0);
            assert!(
                (q - (-x / 2.0f64).exp()).abs() < 1e-12 * (1.0 + 1.0 / q),
                "x = {x}: {q}"
            );
        }
        // Tabulated critical values (5% and 1%).
        for (x, k, p) in [
            (3.841459, 1.0, 0.05),
            (6.634897, 1.0, 0.01),
            (18.307038, 10.0, 0.05),
            (124.342113, 100.0, 0.05),
            (1106.969, 1000.0, 0.01),
        ] {
            let q = chi2_survival(x, k);
            assert!(
                (q - p).abs() < 1e-5 * p.max(1e-3) * 10.0,
                "k = {k}, x = {x}: {q} (expected {p})"
            );
        }
    }

    /// Uniform directions on the sphere from a seeded generator (SplitMix64: consecutive
    /// outputs of a plain 64-bit LCG are too correlated for pairs of numbers).
    fn uniform_samples(n: usize, seed: u64, tilt: f64) -> Vec<[f32; 4]> {
        let mut rng = crate::common::SplitMix64(seed);
        let mut next = move || rng.next_f64();
        (0..n)
            .map(|_| {
                // `tilt` > 0 puts too many samples near the poles: a wrong sampler.
                let u = next();
                let z = (1.0 - 2.0 * u).signum() * (1.0 - 2.0 * u).abs().powf(1.0 + tilt);
                let phi = std::f64::consts::TAU * next();
                let r = (1.0 - z * z).max(0.0).sqrt();
                [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32, 1.0]
            })
            .collect()
    }

    fn uniform_pdf(grid: &SphereBins, sub: usize) -> Vec<f32> {
        vec![(1.0 / (4.0 * std::f64::consts::PI)) as f32; grid.len() * sub * sub]
    }

    #[test]
    fn a_uniform_sampler_passes_and_a_wrong_one_fails() {
        let grid = SphereBins::sphere(16, 32);
        let pdf = uniform_pdf(&grid, 2);
        let alpha = significance(4);
        for seed in [1, 2] {
            let good = goodness_of_fit(&grid, &uniform_samples(200_000, seed, 0.0), &pdf, 2, &[]);
            assert!((good.pdf_integral - 1.0).abs() < 1e-6, "{good:?}");
            assert!(good.passes(alpha), "a uniform sampler fails: {good}");
            // A 5% distortion of cos θ towards the poles is far beyond chance at 2e5 samples.
            let bad = goodness_of_fit(&grid, &uniform_samples(200_000, seed, 0.05), &pdf, 2, &[]);
            assert!(!bad.passes(alpha), "a wrong sampler passes: {bad}");
        }
    }

    #[test]
    fn discrete_outcomes_are_compared_with_their_probabilities() {
        let grid = SphereBins::sphere(8, 16);
        let sub = 1;
        // Half the samples uniform on the sphere, a quarter each to two discrete outcomes.
        let mut samples = uniform_samples(50_000, 3, 0.0);
        samples.extend((0..50_000).map(|i| [0.0, 0.0, 1.0, if i % 2 == 0 { 2.0 } else { 3.0 }]));
        let pdf: Vec<f32> = uniform_pdf(&grid, sub).iter().map(|p| p * 0.5).collect();
        let alpha = significance(2);
        let good = goodness_of_fit(&grid, &samples, &pdf, sub, &[0.25, 0.25]);
        assert!(good.passes(alpha), "{good:?}");
        let bad = goodness_of_fit(&grid, &samples, &pdf, sub, &[0.2, 0.3]);
        assert!(!bad.passes(alpha), "wrong discrete probabilities pass: {bad:?}");
    }

    #[test]
    fn cap_tests_resolve_a_narrow_lobe() {
        // Directions within a 0.05 rad cap around x, drawn uniformly in the cap, against a
        // uniform pdf (passes) and against cos-weighted density around the axis (fails).
        let axis = [1.0, 0.0, 0.0];
        let grid = SphereBins::cap(axis, (0.05f64).cos(), 8, 16);
        let sub = 4;
        let inside: Vec<[f32; 4]> = uniform_samples(100_000, 4, 0.0)
            .into_iter()
            .map(|s| {
                // Map z in [-1, 1] to a cos in [cos_min, 1] about x.
                let c = 1.0 - (1.0 - (0.05f64).cos()) * (1.0 - s[2] as f64) / 2.0;
                let r = (1.0 - c * c).sqrt();
                let phi = (s[1] as f64).atan2(s[0] as f64);
                [c as f32, (r * phi.cos()) as f32, (r * phi.sin()) as f32, 1.0]
            })
            .collect();
        let points = grid.quadrature_points(sub);
        let flat = vec![1.0f32; points.len()];
        let peaked: Vec<f32> = points.iter().map(|p| (p[0] as f64 - 0.9985).max(0.0) as f32).collect();
        let alpha = significance(2);
        let good = goodness_of_fit(&grid, &inside, &flat, sub, &[]);
        assert!(good.passes(alpha), "{good}");
        assert!(!goodness_of_fit(&grid, &inside, &peaked, sub, &[]).passes(alpha));
    }

    #[test]
    fn pooling_merges_cells_expecting_few_samples() {
        let observed = [0.0, 1.0, 2.0, 50.0, 47.0];
        let expected = [1.0, 1.5, 2.5, 48.0, 47.0];
        let (_, dof, _, failure) = pearson(&observed, &expected);
        assert!(failure.is_none());
        // The three small cells (5 expected together) become one: 3 cells, 2 dof.
        assert_eq!(dof, 2);
        // Samples where the pdf is 0: a few in 10^3 are pooled, more fail.
        let (_, _, _, failure) = pearson(&[10.0, 20000.0, 20000.0], &[0.0, 20005.0, 20005.0]);
        assert!(failure.is_none());
        let (_, _, p, failure) = pearson(&[100.0, 20000.0, 20000.0], &[0.0, 20050.0, 20050.0]);
        assert!(failure.is_some() && p == 0.0);
    }
}
