//! Who wins a scene: the target is the best final error of the set (the smallest RMSE any
//! run reached at the end of its budget); each run's time to it is when its curve reached it
//! and stayed at or below it ([`time_to_error`]); the winner reached it first, and runs
//! whose times are within noise of the winner's tie with it.
//!
//! Noise: a run's final error is as uncertain as its curve's tail scatters from sample to
//! sample ([`tail_noise`], relative). As time ∝ RMSE⁻², a relative error σ is 2σ in log time; two
//! times tie when their logs differ by at most [`TIE_STANDARD_ERRORS`] times
//! 2·√(σ₁² + σ₂²). A run that ended above the target counts with the time extrapolated from
//! its end at the Monte Carlo rate: it can tie, never win. So a winner always has the best
//! final error, and one whose final error is only within noise of it ties.

use crate::compare::{ErrorSample, tail_noise, time_to_error};

/// Standard errors within which two runs' times to the target tie.
pub const TIE_STANDARD_ERRORS: f64 = 2.0;

/// Who won a scene.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// No run ended with a finite, positive error.
    Nobody,
    /// This run reached the target first, the others clearly later.
    Winner(usize),
    /// These runs' times to the target are within noise of each other, the first first.
    Tie(Vec<usize>),
}

/// What a scene's runs show.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The best final RMSE of the set (the smallest of the runs' last errors); `None` when no
    /// run ended with a finite, positive one.
    pub best_final_rmse: Option<f64>,
    /// Per run, when it reached that error and stayed at or below it (seconds on its clock,
    /// interpolated log-log between error samples); `None` when its curve ended above it.
    pub time_to_best: Vec<Option<f64>>,
    /// Per run, the relative noise of its final error ([`tail_noise`]); `None` when its
    /// curve is too short to tell (it then counts as 0).
    pub noise: Vec<Option<f64>>,
    /// The winner, or the tie.
    pub outcome: Outcome,
}

/// The verdict on runs with the error curves `curves` (each in time order).
pub fn verdict(curves: &[&[ErrorSample]]) -> Verdict {
    let best = curves
        .iter()
        .filter_map(|c| c.last().map(|s| s.error.rmse))
        .filter(|e| e.is_finite() && *e > 0.0)
        .min_by(f64::total_cmp);
    let times: Vec<Option<(f64, bool)>> = curves.iter().map(|c| time_to_error(c, best?)).collect();
    let noise: Vec<Option<f64>> = curves.iter().map(|c| tail_noise(c)).collect();
    Verdict {
        best_final_rmse: best,
        time_to_best: times.iter().map(|t| t.filter(|t| !t.1).map(|t| t.0)).collect(),
        outcome: outcome(&times, &noise),
        noise,
    }
}

/// The first run to reach the target (a measured time), alone or with those tied with it.
fn outcome(times: &[Option<(f64, bool)>], noise: &[Option<f64>]) -> Outcome {
    let measured = |i: &usize| matches!(times[*i], Some((_, false)));
    let time = |i: usize| times[i].map_or(f64::INFINITY, |t| t.0);
    let Some(first) = (0..times.len())
        .filter(measured)
        .min_by(|&a, &b| time(a).total_cmp(&time(b)))
    else {
        return Outcome::Nobody;
    };
    let sigma = |i: usize| noise[i].unwrap_or(0.0);
    let tied: Vec<usize> = (0..times.len())
        .filter(|&i| {
            let spread = 2.0 * (sigma(i).powi(2) + sigma(first).powi(2)).sqrt();
            i == first || (time(i) / time(first)).ln().abs() <= TIE_STANDARD_ERRORS * spread
        })
        .collect();
    match tied.as_slice() {
        [_] => Outcome::Winner(first),
        _ => Outcome::Tie(tied),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::curve;

    /// A curve at `times` whose RMSE falls as t^-1/2 to `last` at its last sample, each
    /// sample before that times e^(±`scatter`), alternating.
    fn noisy(times: &[f64], last: f64, scatter: f64) -> Vec<ErrorSample> {
        let end = *times.last().expect("a sample");
        let sign = |k: usize| 1.0 - 2.0 * (k % 2) as f64;
        let mut points: Vec<(f64, f64)> = times
            .iter()
            .enumerate()
            .map(|(k, &t)| (t, last * (t / end).powf(-0.5) * (scatter * sign(k)).exp()))
            .collect();
        points.last_mut().expect("a sample").1 = last;
        curve(&points)
    }

    /// 12 log-spaced sample times from `from` to `to` seconds.
    fn log_times(from: f64, to: f64) -> Vec<f64> {
        (0..12).map(|k| from * (to / from).powf(k as f64 / 11.0)).collect()
    }

    #[test]
    fn a_dip_below_the_target_does_not_win() {
        // A reaches 0.1 at its end. B dips to 0.05 at t = 2 and ends at 0.2: clearly above,
        // not a winner, not tied.
        let a = curve(&[(1.0, 1.0), (10.0, 0.1)]);
        let b = curve(&[(1.0, 0.4), (2.0, 0.05), (10.0, 0.2)]);
        let v = verdict(&[&a, &b]);
        assert_eq!(v.best_final_rmse, Some(0.1));
        assert_eq!(v.time_to_best, vec![Some(10.0), None]);
        assert_eq!(v.outcome, Outcome::Winner(0));
    }

    #[test]
    fn a_late_crossing_that_stays_wins_over_an_earlier_dip() {
        // A falls toward 0.13 and dips once below 0.1, at 1.6 s; B reaches 0.1 at its end,
        // 3 s, later. Both scatter by 1%.
        let times = log_times(0.1, 3.0);
        let mut a = noisy(&times, 0.13, 0.01);
        a[9].error.rmse = 0.095;
        let b = noisy(&times, 0.1, 0.01);
        let v = verdict(&[&a, &b]);
        assert!(
            a[9].seconds < 2.0 && v.noise[0].is_some_and(|n| n < 0.05),
            "{:?}",
            v.noise
        );
        assert_eq!(v.time_to_best[0], None);
        assert!(v.time_to_best[1].is_some_and(|t| (t - 3.0).abs() < 1e-9));
        assert_eq!(v.outcome, Outcome::Winner(1));
    }

    #[test]
    fn equal_runs_and_runs_within_noise_tie_and_broken_curves_win_nothing() {
        let a = curve(&[(1.0, 0.5), (2.0, 0.2)]);
        let v = verdict(&[&a, &a.clone()]);
        assert_eq!(v.time_to_best, vec![Some(2.0), Some(2.0)]);
        assert_eq!(v.outcome, Outcome::Tie(vec![0, 1]), "equal times tie without noise");
        // Both scatter by 5% about t^-1/2: 1% apart at the end is a tie; with 2%, 30% apart is not.
        let times = log_times(0.1, 3.0);
        let a = noisy(&times, 0.1, 0.05);
        let close = noisy(&times, 0.101, 0.05);
        let v = verdict(&[&a, &close]);
        assert!(v.noise.iter().all(|n| n.is_some_and(|n| n > 0.03)), "{:?}", v.noise);
        assert_eq!(v.outcome, Outcome::Tie(vec![0, 1]));
        let (b, far) = (noisy(&times, 0.1, 0.02), noisy(&times, 0.13, 0.02));
        assert_eq!(verdict(&[&far, &b]).outcome, Outcome::Winner(1));
        let nan = curve(&[(1.0, f64::NAN)]);
        let v = verdict(&[&nan, &[]]);
        assert_eq!(v.best_final_rmse, None);
        assert_eq!(v.time_to_best, vec![None, None]);
        assert_eq!(v.outcome, Outcome::Nobody);
    }

    #[test]
    fn cornell_glossy_sun_a_dip_winner_with_a_worse_final_error_is_not_the_winner() {
        // Issue 40: 48x48, 3 s. PT's curve is smooth and ends at 6.60e-2; LVC-BPT's (its first
        // sample at 1.87 s: the compile was on the clock) scatters by 3%, dips below 6.60e-2
        // once, at 2.75 s, and ends at 6.69e-2. The old rule (first to touch the target) named
        // LVC-BPT.
        let pt = noisy(&log_times(0.2, 3.0), 6.60e-2, 0.01);
        let mut bpt = noisy(&log_times(1.87, 3.0), 6.69e-2, 0.03);
        bpt[9].error.rmse = 6.5e-2;
        let v = verdict(&[&pt, &bpt]);
        assert_eq!(v.best_final_rmse, Some(6.60e-2));
        assert_eq!(v.time_to_best[1], None, "LVC-BPT ended above the target");
        assert!(v.time_to_best[0].is_some_and(|t| (t - 3.0).abs() < 1e-9));
        assert_ne!(v.outcome, Outcome::Winner(1));
        // 1.4% apart, LVC-BPT's curve scattering by 3% (the dip does not count): a tie, PT
        // first.
        assert_eq!(v.outcome, Outcome::Tie(vec![0, 1]));
        // LVC-BPT's curve 25% above all along: PT wins alone.
        let worse = noisy(&log_times(1.87, 3.0), 6.60e-2 * 1.25, 0.03);
        assert_eq!(verdict(&[&pt, &worse]).outcome, Outcome::Winner(0));
    }
}
