//! A pass rate with its confidence interval, as every batch of trials reports it.
//!
//! The interval is Clopper–Pearson's exact one: the set of success probabilities under which
//! the observed count is not in either tail beyond `(1 − confidence) / 2`. It is chosen over
//! Wilson's score interval because verification lives at the edge: a ground truth passes
//! 100 % or nearly, and near 0 or 1 Wilson's interval covers less often than it claims, while
//! Clopper–Pearson's covers at least as often as it claims for every success probability (it
//! is conservative, a little wider than needed). At 300 of 300 it reads 98.8–100 %.

use serde::{Deserialize, Serialize};
use statrs::distribution::{Beta, ContinuousCDF};
use std::fmt;

/// The confidence of the intervals reported (two-sided).
pub const CONFIDENCE: f64 = 0.95;

/// How many trials passed, and the confidence interval of the success probability.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PassRate {
    /// Trials that passed.
    pub passed: usize,
    /// Trials run.
    pub trials: usize,
    /// Lower end of the interval (0–1).
    pub lower: f64,
    /// Upper end of the interval (0–1).
    pub upper: f64,
    /// Its confidence (two-sided), e.g. 0.95.
    pub confidence: f64,
}

impl PassRate {
    /// `passed` of `trials` with the 95 % interval ([`CONFIDENCE`]).
    pub fn new(passed: usize, trials: usize) -> PassRate {
        PassRate::with_confidence(passed, trials, CONFIDENCE)
    }

    /// `passed` of `trials` with the interval at `confidence` (in (0, 1); `passed` is capped
    /// at `trials`). No trials give the whole of [0, 1].
    pub fn with_confidence(passed: usize, trials: usize, confidence: f64) -> PassRate {
        let passed = passed.min(trials);
        let tail = 0.5 * (1.0 - confidence);
        PassRate {
            passed,
            trials,
            lower: clopper_pearson_lower(passed, trials, tail),
            upper: 1.0 - clopper_pearson_lower(trials - passed, trials, tail),
            confidence,
        }
    }

    /// The share that passed (0 when nothing ran).
    pub fn rate(&self) -> f64 {
        if self.trials == 0 {
            0.0
        } else {
            self.passed as f64 / self.trials as f64
        }
    }
}

impl fmt::Display for PassRate {
    /// `97/100 (97.0 %, 95 % CI 91.5–99.4 %)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}/{} ({}, {:.0} % CI {}–{})",
            self.passed,
            self.trials,
            percent(self.rate()),
            100.0 * self.confidence,
            percent(self.lower),
            percent(self.upper)
        )
    }
}

/// A share as a percentage with one decimal (two where one would round 99.95 % up to 100 %).
pub fn percent(share: f64) -> String {
    let p = 100.0 * share;
    if p > 99.9 && p < 100.0 {
        format!("{p:.2} %")
    } else {
        format!("{p:.1} %")
    }
}

/// The largest success probability under which `successes` or more of `trials` happen with
/// probability at most `tail`: the one-sided Clopper–Pearson lower bound (the `tail`-quantile
/// of Beta(successes, trials − successes + 1)); 0 when there are no successes.
pub(crate) fn clopper_pearson_lower(successes: usize, trials: usize, tail: f64) -> f64 {
    if successes == 0 || trials == 0 {
        return 0.0;
    }
    let a = successes as f64;
    let b = (trials - successes) as f64 + 1.0;
    match Beta::new(a, b) {
        Ok(beta) => beta.inverse_cdf(tail),
        Err(_) => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bounds_match_the_closed_forms_at_the_ends() {
        // All passed: the lower bound solves p^n = tail.
        let all = PassRate::new(300, 300);
        assert!(
            (all.lower - 0.025f64.powf(1.0 / 300.0)).abs() < 1e-10,
            "{all:?}"
        );
        assert_eq!(all.upper, 1.0);
        // None passed: the mirror image.
        let none = PassRate::new(0, 300);
        assert_eq!(none.lower, 0.0);
        assert!((none.upper - (1.0 - 0.025f64.powf(1.0 / 300.0))).abs() < 1e-10);
        // Reference values (scipy.stats.beta.ppf).
        let some = PassRate::new(97, 100);
        assert!((some.lower - 0.914_823_947).abs() < 1e-8, "{some:?}");
        assert!((some.upper - 0.993_770_028).abs() < 1e-8, "{some:?}");
    }

    #[test]
    fn the_interval_holds_the_rate_and_narrows_with_trials() {
        let few = PassRate::new(19, 20);
        let many = PassRate::new(950, 1000);
        for r in [few, many] {
            assert!(r.lower < r.rate() && r.rate() < r.upper, "{r:?}");
        }
        assert!(many.upper - many.lower < few.upper - few.lower);
        let nothing = PassRate::new(0, 0);
        assert_eq!((nothing.lower, nothing.upper), (0.0, 1.0));
        assert_eq!(
            PassRate::new(97, 100).to_string(),
            "97/100 (97.0 %, 95 % CI 91.5 %–99.4 %)"
        );
    }

    /// Coverage: over every success probability on a grid, the share of outcomes whose
    /// interval holds it is at least the confidence (computed exactly over the binomial).
    #[test]
    fn the_interval_covers_at_least_as_often_as_it_claims() {
        use statrs::distribution::{Binomial, Discrete};
        let n = 50;
        let intervals: Vec<PassRate> = (0..=n).map(|k| PassRate::new(k, n)).collect();
        for i in 1..200 {
            let p = f64::from(i) / 200.0;
            let binomial = Binomial::new(p, n as u64).unwrap();
            let covered: f64 = intervals
                .iter()
                .filter(|r| r.lower <= p && p <= r.upper)
                .map(|r| binomial.pmf(r.passed as u64))
                .sum();
            assert!(covered >= CONFIDENCE - 1e-9, "p = {p}: {covered}");
        }
    }
}
