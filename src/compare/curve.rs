//! An error curve's arithmetic: when it reaches an error and stays there, its convergence
//! slope, and the scatter of its tail, which stands for the noise of its final error.

use super::ErrorSample;

/// The samples with a finite, positive error at a positive time, in time order.
fn usable(samples: &[ErrorSample]) -> Vec<&ErrorSample> {
    let ok = |s: &&ErrorSample| s.error.rmse.is_finite() && s.error.rmse > 0.0 && s.seconds > 0.0;
    samples.iter().filter(ok).collect()
}

/// When a curve reaches RMSE `target` **and stays at or below it** to its end: interpolated
/// log-log between its last sample above the target and the one after it, or the first
/// sample's time when none is above. A noisy curve that dips below the target and comes
/// back up has not reached it. When the last sample is above the target, the time is
/// extrapolated from it at the Monte Carlo rate (time ∝ RMSE⁻²). Returns the time and
/// whether it was extrapolated; `None` for a curve without a usable sample.
pub fn time_to_error(samples: &[ErrorSample], target: f64) -> Option<(f64, bool)> {
    let curve = usable(samples);
    let last = *curve.last()?;
    if last.error.rmse > target {
        return Some((last.seconds * (last.error.rmse / target).powi(2), true));
    }
    let Some(above) = curve.iter().rposition(|s| s.error.rmse > target) else {
        return Some((curve[0].seconds, false));
    };
    let (a, b) = (curve[above], curve[above + 1]);
    if b.error.rmse == target {
        return Some((b.seconds, false));
    }
    let f = (target.ln() - a.error.rmse.ln()) / (b.error.rmse.ln() - a.error.rmse.ln());
    Some(((a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp(), false))
}

/// The tail of a curve in log-log: (log of the time since its first error sample, log RMSE)
/// over the last decade and a half of that time (so the set-up and first-frame cost, a
/// constant offset, does not bend the line).
fn tail(samples: &[ErrorSample]) -> Vec<(f64, f64)> {
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Vec::new();
    };
    let from = (last.seconds - first.seconds) / 10f64.powf(1.5);
    samples
        .iter()
        .map(|s| (s.seconds - first.seconds, s.error.rmse))
        .filter(|&(t, e)| t > 0.0 && t >= from && e > 0.0 && e.is_finite())
        .map(|(t, e)| (t.ln(), e.ln()))
        .collect()
}

/// The least-squares line through `points`: (slope, intercept); `None` when their x are all
/// equal.
fn line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| (sxy / sxx, my - sxy / sxx * mx))
}

/// The convergence rate of a curve: the least-squares slope of log RMSE against log of the
/// time since its first error sample, over the last decade and a half of that time. −1/2 is
/// the Monte Carlo rate. `None` with fewer than 3 samples there.
pub fn convergence_slope(samples: &[ErrorSample]) -> Option<f64> {
    let points = tail(samples);
    if points.len() < 3 {
        return None;
    }
    line(&points).map(|(slope, _)| slope)
}

/// The noise of a curve's final error, relative: the scatter σ of its log RMSE from sample
/// to sample over the same tail as [`convergence_slope`]. Taken from the second differences
/// d = y₍ₖ₎ − (y₍ₖ₋₁₎ + y₍ₖ₊₁₎)/2 of the log RMSE y, which a smooth trend (a line, or one
/// that bends as a bias levels the error off) barely moves and whose standard deviation is
/// σ·√1.5 for independent scatter; as the median |d| × 1.4826 / √1.5, so that one wild
/// sample does not make a curve look noisy. `None` with fewer than 4 samples in the tail.
pub fn tail_noise(samples: &[ErrorSample]) -> Option<f64> {
    let logs: Vec<f64> = tail(samples).into_iter().map(|(_, y)| y).collect();
    if logs.len() < 4 {
        return None;
    }
    let mut d: Vec<f64> = logs.windows(3).map(|w| (w[1] - (w[0] + w[2]) / 2.0).abs()).collect();
    d.sort_by(f64::total_cmp);
    let median = match d.len() % 2 {
        1 => d[d.len() / 2],
        _ => (d[d.len() / 2 - 1] + d[d.len() / 2]) / 2.0,
    };
    Some(median * 1.4826 / 1.5f64.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::curve;

    #[test]
    fn time_to_error_interpolates_and_extrapolates() {
        // RMSE = t^-1/2: 1 at t = 1, 0.5 at t = 4.
        let c = curve(&[(1.0, 1.0), (4.0, 0.5), (16.0, 0.25)]);
        let (t, x) = time_to_error(&c, 0.5f64.powf(1.5)).unwrap();
        assert!(!x && (t - 8.0).abs() < 1e-9, "{t}");
        let (t, x) = time_to_error(&c, 0.125).unwrap();
        assert!(x && (t - 64.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to_error(&c, 2.0), Some((1.0, false)));
        assert_eq!(time_to_error(&curve(&[(1.0, f64::NAN)]), 1.0), None);
    }

    #[test]
    fn a_dip_below_the_target_that_comes_back_up_is_not_reaching_it() {
        // Below 0.3 at t = 2 (one noisy sample), back above at t = 4, below for good from t = 8.
        let c = curve(&[(1.0, 0.5), (2.0, 0.25), (4.0, 0.4), (8.0, 0.2), (16.0, 0.15)]);
        let (t, x) = time_to_error(&c, 0.3).unwrap();
        // log-log between (4, 0.4) and (8, 0.2): log t = log 4 + log(0.4 / 0.3) / log 2 · log 2.
        assert!(!x && (t - 4.0 * 0.4 / 0.3).abs() < 1e-9, "{t}");
        // A curve that dips and ends above has not reached it: extrapolated from its end.
        let ends_above = curve(&[(1.0, 0.5), (2.0, 0.25), (4.0, 0.4)]);
        let (t, x) = time_to_error(&ends_above, 0.3).unwrap();
        assert!(x && (t - 4.0 * (0.4f64 / 0.3).powi(2)).abs() < 1e-9, "{t}");
    }

    #[test]
    fn slope_of_a_monte_carlo_curve_after_a_start_up_delay() {
        // RMSE = (t - 2)^-1/2 from a first sample at t = 2 (when the first frame is done).
        let mut points = vec![(2.0, 3.0)];
        points.extend([1.0, 4.0, 16.0, 64.0].map(|dt: f64| (2.0 + dt, dt.powf(-0.5))));
        let slope = convergence_slope(&curve(&points)).unwrap();
        assert!((slope + 0.5).abs() < 1e-12, "{slope}");
        assert_eq!(convergence_slope(&curve(&points[..3])), None);
    }

    #[test]
    fn tail_noise_is_the_scatter_about_the_trend_and_ignores_one_wild_sample() {
        // t^-1/2 at t = 1, √2, 2, ... 256, times e^(±0.1) alternating: every second
        // difference of the log is ±0.2 (alternation is the worst case: independent scatter of
        // 0.1 would give 0.1), so σ = 0.2 · 1.4826 / √1.5.
        let mut points: Vec<(f64, f64)> = (0..17)
            .map(|k| {
                let t = 2f64.powf(k as f64 / 2.0);
                (t, t.powf(-0.5) * (0.1 * (1.0 - 2.0 * (k % 2) as f64)).exp())
            })
            .collect();
        let expected = 0.2 * 1.4826 / 1.5f64.sqrt();
        let noise = tail_noise(&curve(&points)).unwrap();
        assert!((noise - expected).abs() < 1e-9, "{noise}");
        // A smooth curve has none, and one wild sample among the tail's ten leaves it so.
        let smooth: Vec<(f64, f64)> = points.iter().map(|&(t, _)| (t, t.powf(-0.5))).collect();
        assert!(tail_noise(&curve(&smooth)).unwrap() < 1e-12);
        let mut wild = smooth.clone();
        wild[12].1 *= 0.5;
        assert!(tail_noise(&curve(&wild)).unwrap() < 1e-12);
        points.truncate(4);
        assert_eq!(tail_noise(&curve(&points)), None, "three samples after the first");
    }
}
