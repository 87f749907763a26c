//! Light selection in proportion to estimated power: Walker's alias method, with Vose's
//! construction ("A linear algorithm for generating random numbers with a given
//! distribution", 1991), built on the host in f64. Picking on the GPU costs one table read
//! whatever the number of lights.

use crate::gpu::GpuAliasEntry;

/// The alias table of non-negative `weights` (their sum need not be 1). When every weight
/// is zero (or the list is empty), the table picks uniformly. Weights that are not finite
/// count as zero.
pub fn build(weights: &[f64]) -> Vec<GpuAliasEntry> {
    let n = weights.len();
    let clean: Vec<f64> = weights
        .iter()
        .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
        .collect();
    let total: f64 = clean.iter().sum();
    let pmf: Vec<f64> = if total > 0.0 {
        clean.iter().map(|w| w / total).collect()
    } else {
        vec![1.0 / n as f64; n]
    };
    // Scaled so the mean is 1: slots below 1 are filled up by one slot above 1.
    let mut scaled: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
    let mut entries: Vec<GpuAliasEntry> = (0..n)
        .map(|i| GpuAliasEntry {
            threshold: 1.0,
            other: i as u32,
            pmf: pmf[i] as f32,
        })
        .collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        entries[s].threshold = scaled[s] as f32;
        entries[s].other = l as u32;
        scaled[l] = (scaled[l] + scaled[s]) - 1.0;
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What remains is 1 up to rounding: those slots keep their own light.
    entries
}

/// The probability with which `table` picks each light, as the GPU's `pick_light` does:
/// slot `i` is chosen with probability 1/n, then keeps `i` with probability `threshold`.
pub fn implied_probabilities(table: &[GpuAliasEntry]) -> Vec<f64> {
    let n = table.len() as f64;
    let mut p = vec![0.0; table.len()];
    for (i, e) in table.iter().enumerate() {
        let keep = (e.threshold as f64).clamp(0.0, 1.0);
        p[i] += keep / n;
        p[e.other as usize] += (1.0 - keep) / n;
    }
    p
}

/// Rec. 709 luminance of linear RGB (the weights of `luminance` in the WGSL).
pub fn luminance(c: [f32; 3]) -> f64 {
    0.212671 * c[0] as f64 + 0.71516 * c[1] as f64 + 0.072169 * c[2] as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of weights over nine orders of magnitude, with zeros.
    fn weights(n: usize) -> Vec<f64> {
        let mut x = 12345u64;
        (0..n)
            .map(|i| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                if i % 7 == 3 {
                    0.0
                } else {
                    10f64.powf((x >> 11) as f64 / (1u64 << 53) as f64 * 9.0 - 4.0)
                }
            })
            .collect()
    }

    /// The table's implied probabilities equal the normalised weights. Each slot's share is
    /// its f32 threshold (relative rounding 2^-24 = 6e-8) plus the f32 shares of the slots
    /// aliasing to it, so 1e-6 relative (or 1e-9 absolute, for tiny weights) bounds the
    /// rounding; a wrong alias or threshold moves some probability by at least a slot's 1/n.
    #[test]
    fn implied_probabilities_equal_the_normalised_weights() {
        for n in [1, 2, 3, 10, 1000, 4097] {
            let w = weights(n);
            let total: f64 = w.iter().sum();
            let table = build(&w);
            assert_eq!(table.len(), n);
            for (i, (p, e)) in implied_probabilities(&table).iter().zip(&table).enumerate() {
                let exact = w[i] / total;
                assert!(
                    (p - exact).abs() <= 1e-6 * exact + 1e-9,
                    "n {n}, light {i}: implied {p}, normalised weight {exact}"
                );
                assert!(((e.pmf as f64) - exact).abs() <= 1e-7 * exact, "pmf of light {i}");
                if w[i] == 0.0 {
                    assert_eq!(e.threshold, 0.0, "a light without power is never kept");
                }
            }
        }
    }

    #[test]
    fn zero_and_invalid_weights() {
        let table = build(&[0.0, 0.0, 0.0, 0.0]);
        assert_eq!(implied_probabilities(&table), vec![0.25; 4], "all zero: uniform");
        let table = build(&[f64::NAN, 1.0, f64::INFINITY, -2.0]);
        assert_eq!(implied_probabilities(&table), vec![0.0, 1.0, 0.0, 0.0]);
        assert!(build(&[]).is_empty());
    }

    #[test]
    fn a_wrong_table_is_detected() {
        let w = weights(64);
        let mut table = build(&w);
        let moved = table.iter().position(|e| e.threshold < 0.5).unwrap();
        table[moved].other = (table[moved].other + 1) % 64;
        let total: f64 = w.iter().sum();
        let worst = implied_probabilities(&table)
            .iter()
            .zip(&w)
            .map(|(p, w)| (p - w / total).abs())
            .fold(0.0, f64::max);
        assert!(worst > 1e-3, "a redirected alias changes the probabilities by {worst}");
    }
}
