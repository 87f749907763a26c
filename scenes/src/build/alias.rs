//! Light selection in proportion to estimated power: Walker's alias method, with Vose's
//! construction ("A linear algorithm for generating random numbers with a given
//! distribution", 1991), in integers, so that the probability the GPU picks a light with is
//! exactly the one it divides by. Picking on the GPU costs one table read whatever the number
//! of lights.
//!
//! The GPU picks from the [`PICK_BITS`] bits of one uniform number (`pick_light` in
//! shaders/lib/lights.wgsl): the top ones choose one of the table's 2^m slots (the lights,
//! padded to a power of two), the rest whether the slot keeps its own light (`keep` of the slot's
//! 2^(24 - m) values do) or gives its `other`. Each light is therefore picked for a whole
//! number of the 2^24 values, and its `pmf` is that number over 2^24, exactly. A light with
//! power gets at least one value, so every light that emits can be picked.
//!
//! (The table once held each slot's share as an f32 threshold compared with the fraction of
//! `u × lights`: with 10^5 lights that fraction has only 7 bits, so lights with small shares
//! were picked up to 2.5 times as often as their `pmf` said. Next-event estimation and light
//! tracing then over-counted small bright emitters beside large ones: a sphere of radius 0.03
//! beside one of radius 0.5 lit the floor under it 3% too brightly.)

use crate::gpu::GpuAliasEntry;
/// The luminance by which light powers weigh radiance.
pub use crate::model::luminance;

/// Random bits a pick uses.
pub const PICK_BITS: u32 = 24;

/// The most lights a table can pick from: each needs a value of its own.
pub const MAX_LIGHTS: usize = 1 << PICK_BITS;

/// The number of values of the [`PICK_BITS`] bits.
const VALUES: u64 = 1 << PICK_BITS;

/// The alias table of non-negative `weights` (their sum need not be 1), `weights.len()`
/// rounded up to a power of two entries. When every weight is zero, the table picks
/// uniformly. Weights that are not finite count as zero. More than [`MAX_LIGHTS`] weights
/// are an error.
pub fn build(weights: &[f64]) -> Result<Vec<GpuAliasEntry>, String> {
    let n = weights.len();
    if n > MAX_LIGHTS {
        return Err(format!(
            "{n} lights (emissive triangles and others): light selection picks from at most {MAX_LIGHTS}"
        ));
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let counts = value_counts(weights);
    let slots = n.next_power_of_two();
    let per_slot = VALUES / slots as u64;
    let mut need: Vec<u64> = (0..slots).map(|i| counts.get(i).map_or(0, |&c| c as u64)).collect();
    let mut entries: Vec<GpuAliasEntry> = (0..slots)
        .map(|i| GpuAliasEntry {
            keep: per_slot as u32,
            other: i as u32,
            pmf: counts.get(i).map_or(0.0, |&c| (c as f64 / VALUES as f64) as f32),
        })
        .collect();
    // Vose: a slot short of `per_slot` values is filled up by a slot that has more. The
    // shortfalls add up to the excesses exactly, so every slot ends full.
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..slots).partition(|&i| need[i] < per_slot);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        entries[s].keep = need[s] as u32;
        entries[s].other = l as u32;
        need[l] -= per_slot - need[s];
        if need[l] < per_slot {
            large.pop();
            small.push(l);
        }
    }
    debug_assert!(small.is_empty() && large.iter().all(|&l| need[l] == per_slot));
    Ok(entries)
}

/// How many of the 2^[`PICK_BITS`] values pick each light: one for every light with weight
/// whose share is smaller, the rest in proportion to the weights, rounded by largest
/// remainders, summing to 2^PICK_BITS. `weights.len()` is at most [`MAX_LIGHTS`].
fn value_counts(weights: &[f64]) -> Vec<u32> {
    let clean: Vec<f64> = weights
        .iter()
        .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
        .collect();
    let total: f64 = clean.iter().sum();
    let share: Vec<f64> = if total > 0.0 {
        clean.iter().map(|w| w / total * VALUES as f64).collect()
    } else {
        vec![VALUES as f64 / weights.len() as f64; weights.len()]
    };
    // Lights whose share is under one value get one; the others share what is left in
    // proportion (which may take another light under one: repeat until none does).
    let mut held: Vec<bool> = share.iter().map(|&s| s > 0.0 && s < 1.0).collect();
    let scale = loop {
        let ones = held.iter().filter(|&&h| h).count() as f64;
        let rest: f64 = share.iter().zip(&held).filter(|(_, h)| !**h).map(|(s, _)| s).sum();
        let scale = (VALUES as f64 - ones) / rest;
        let mut changed = false;
        for (h, &s) in held.iter_mut().zip(&share) {
            if !*h && s > 0.0 && s * scale < 1.0 {
                *h = true;
                changed = true;
            }
        }
        if !changed {
            break scale;
        }
    };
    let scaled: Vec<f64> = share
        .iter()
        .zip(&held)
        .map(|(&s, &h)| if h { 1.0 } else { s * scale })
        .collect();
    let mut counts: Vec<u64> = scaled.iter().map(|&s| s.floor() as u64).collect();
    // The values rounding left go to the largest remainders.
    let assigned: u64 = counts.iter().sum();
    let mut order: Vec<usize> = (0..counts.len()).filter(|&i| scaled[i] > 0.0).collect();
    order.sort_by(|&a, &b| (scaled[b] - scaled[b].floor()).total_cmp(&(scaled[a] - scaled[a].floor())));
    for &i in order.iter().cycle().take(VALUES.saturating_sub(assigned) as usize) {
        counts[i] += 1;
    }
    // (Rounding of the sum can leave a value too many: it comes off the smallest remainder.)
    let mut excess = assigned.saturating_sub(VALUES);
    for &i in order.iter().rev() {
        if excess > 0 && counts[i] > 1 {
            counts[i] -= 1;
            excess -= 1;
        }
    }
    counts.into_iter().map(|c| c as u32).collect()
}

/// The right shift that takes a pick's [`PICK_BITS`] bits to a slot of a table for `lights`
/// lights (`countLeadingZeros(lights - 1) - 8` in the WGSL).
pub fn slot_shift(lights: usize) -> u32 {
    PICK_BITS - lights.next_power_of_two().trailing_zeros()
}

/// The light `table` (built for `lights` lights) picks for the value `bits` of the
/// [`PICK_BITS`] random bits, as the GPU's `pick_light` does.
pub fn pick(table: &[GpuAliasEntry], lights: usize, bits: u32) -> u32 {
    let shift = slot_shift(lights);
    let slot = bits >> shift;
    let entry = table[slot as usize];
    if bits & ((1u32 << shift) - 1) < entry.keep {
        slot
    } else {
        entry.other
    }
}

/// How many of the 2^[`PICK_BITS`] values pick each of the `lights` lights of `table`.
pub fn implied_counts(table: &[GpuAliasEntry], lights: usize) -> Vec<u64> {
    let per_slot = 1u64 << slot_shift(lights);
    let mut counts = vec![0u64; table.len()];
    for (i, e) in table.iter().enumerate() {
        let keep = (e.keep as u64).min(per_slot);
        counts[i] += keep;
        counts[e.other as usize] += per_slot - keep;
    }
    counts.truncate(lights);
    counts
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

    /// Two emitting spheres meshed as Mitsuba's are (65,536 triangles each, their areas
    /// falling towards the poles): radius 0.5 and radiance 800, radius 0.03 and radiance
    /// 901.8; the small one has 0.16% of the power, its triangles 2^-24 to 10^-7 each.
    fn two_spheres() -> Vec<f64> {
        let mut w = Vec::new();
        for (radius, radiance) in [(0.5f64, 800.0f64), (0.03, 901.8)] {
            let (rows, columns) = (128, 256);
            for j in 0..rows {
                let band = |j: usize| (std::f64::consts::PI * j as f64 / rows as f64).cos();
                let quad = radius * radius * (band(j) - band(j + 1)) * std::f64::consts::TAU / columns as f64;
                let triangles = if j == 0 || j == rows - 1 { 1 } else { 2 };
                for _ in 0..columns * triangles {
                    w.push(std::f64::consts::PI * radiance * quad / triangles as f64);
                }
            }
        }
        w
    }

    /// Each light is picked for exactly `pmf` × 2^24 of the 2^24 values, and that is its
    /// normalised weight rounded to a value (or one value, for a light with weight whose share
    /// is smaller, the values it takes coming from the largest lights): the GPU divides by the
    /// probability it picks with.
    fn assert_exact(w: &[f64]) {
        let table = build(w).unwrap();
        assert_eq!(table.len(), w.len().next_power_of_two());
        let counts = implied_counts(&table, w.len());
        let total: f64 = w.iter().sum();
        for (i, (&c, e)) in counts.iter().zip(&table).enumerate() {
            assert_eq!(
                e.pmf as f64 * VALUES as f64,
                c as f64,
                "light {i}: pmf against the values that pick it"
            );
            let share = w[i] / total * VALUES as f64;
            if w[i] == 0.0 {
                assert_eq!(c, 0, "a light without power is never picked");
            } else {
                // Within one value of the share, but for the values the lights raised to one
                // took from the others: at most their number over 2^24 of a share.
                let slack = 1.0 + share * w.len() as f64 / VALUES as f64;
                assert!(
                    c >= 1 && (c as f64 - share).abs() <= slack,
                    "light {i}: {c} values for a share of {share}"
                );
            }
        }
        assert_eq!(counts.iter().sum::<u64>(), VALUES);
    }

    #[test]
    fn every_light_is_picked_with_its_pmf_exactly() {
        for n in [1, 2, 3, 10, 1000, 4097] {
            assert_exact(&weights(n));
        }
        assert_exact(&two_spheres());
    }

    /// `pick`, run over every value of the bits, picks each light as often as
    /// `implied_counts` says: the counting mirrors the picking (which mirrors the WGSL).
    #[test]
    fn picking_every_value_counts_as_implied() {
        for w in [weights(4097), two_spheres()] {
            let table = build(&w).unwrap();
            let mut seen = vec![0u64; w.len()];
            for bits in 0..VALUES as u32 {
                seen[pick(&table, w.len(), bits) as usize] += 1;
            }
            assert_eq!(seen, implied_counts(&table, w.len()));
        }
    }

    /// The small sphere of `two_spheres`, with the table picked as it once was (an f32
    /// threshold against the fraction of u × lights), got 1.5 times its pmf: the test of the
    /// exact counts would have failed.
    #[test]
    fn the_old_fractional_pick_over_picks_small_lights() {
        let w = two_spheres();
        let n = w.len();
        let total: f64 = w.iter().sum();
        let p: Vec<f64> = w.iter().map(|x| x / total).collect();
        let mut scaled: Vec<f64> = p.iter().map(|x| x * n as f64).collect();
        let (mut threshold, mut other) = (vec![1.0f32; n], (0..n).collect::<Vec<_>>());
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            threshold[s] = scaled[s] as f32;
            other[s] = l;
            scaled[l] = (scaled[l] + scaled[s]) - 1.0;
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        let mut picked_small = 0u64;
        for k in 0..VALUES as u32 {
            let x = (k as f32 / VALUES as f32) * n as f32;
            let slot = (x as usize).min(n - 1);
            let index = if x - (slot as f32) < threshold[slot] {
                slot
            } else {
                other[slot]
            };
            picked_small += (index >= n / 2) as u64;
        }
        let pmf_small: f64 = p[n / 2..].iter().sum();
        let ratio = picked_small as f64 / VALUES as f64 / pmf_small;
        assert!(
            ratio > 1.2,
            "the old pick picked the small sphere {ratio} times its pmf"
        );
    }

    #[test]
    fn zero_invalid_and_too_many_weights() {
        let uniform = build(&[0.0, 0.0, 0.0, 0.0]).unwrap();
        assert_eq!(implied_counts(&uniform, 4), vec![VALUES / 4; 4], "all zero: uniform");
        let table = build(&[f64::NAN, 1.0, f64::INFINITY, -2.0]).unwrap();
        assert_eq!(implied_counts(&table, 4), vec![0, VALUES, 0, 0]);
        assert!(build(&[]).unwrap().is_empty());
        let err = build(&vec![1.0; MAX_LIGHTS + 1]).unwrap_err();
        assert!(err.contains("16777217 lights") && err.contains("16777216"), "{err}");
    }

    #[test]
    fn a_wrong_table_is_detected() {
        let w = weights(64);
        let mut table = build(&w).unwrap();
        let moved = table.iter().position(|e| e.keep < VALUES as u32 / 128).unwrap();
        table[moved].other = (table[moved].other + 1) % 64;
        let counts = implied_counts(&table, 64);
        assert!(
            counts
                .iter()
                .zip(&table)
                .any(|(&c, e)| c as f64 != e.pmf as f64 * VALUES as f64),
            "a redirected alias changes the counts"
        );
    }
}
