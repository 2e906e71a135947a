//! The sequential deployment gate: does a spec succeed with probability at least `P`, at
//! confidence `C`?
//!
//! **The rule** (a sequential exact-interval rule). Trials are judged one by one in seed
//! order. After `n` trials with `k` failures the gate
//! - *passes* once the one-sided Clopper–Pearson upper bound of the failure probability at
//!   confidence `C` is at most `1 − P`: were the failure probability above `1 − P`, `k` or
//!   fewer failures in `n` trials would happen with probability at most `1 − C`;
//! - *fails* once the one-sided lower bound exceeds `1 − P`: were it at most `1 − P`, `k` or
//!   more failures would happen with probability below `1 − C`;
//! - is *undecided* when neither happened within `max_trials`.
//!
//! Both tests are binomial tail sums at the one probability `1 − P`, so the gate's boundaries
//! are computed once, exactly (statrs' regularized incomplete beta), for every `n` up to
//! `max_trials`: the largest failure count that passes and the smallest that fails.
//!
//! **What it guarantees.** Looking after every trial makes each look's confidence an upper
//! bound on the rule's, so the gate is judged by its operating characteristic, computed
//! exactly by [`Gate::operating_characteristic`] (a walk over every (trials, failures) state
//! that no boundary has absorbed). With the defaults ([`GateOptions::default`]: P = 0.99,
//! C = 0.95, 2,000 trials at most):
//!
//! | failure probability | passes | fails | undecided | mean trials |
//! |---|---|---|---|---|
//! | 0 | 100 % | 0 | 0 | 299 |
//! | 0.1 % | 99.45 % | 0.55 % | 0 | 356 |
//! | 0.5 % | 85.9 % | 4.4 % | 9.7 % | 862 |
//! | 1 % (the boundary) | 16.4 % | 25.6 % | 58.0 % | 1,386 |
//! | 2 % | 0.30 % | 98.9 % | 0.78 % | 359 |
//! | 100 % | 0 | 100 % | 0 | 1 |
//!
//! So the region where the gate is indifferent is between about 0.2 % and 2 % of failures;
//! Wald's SPRT between 0.1 % and 2 % at α = β = 0.05 was measured beside it and misses one
//! bound once truncated (a 2 % spec fails only 94.9 % of its gates), which is why this rule
//! is used. A spec that never fails passes at trial 299.

use serde::{Deserialize, Serialize};
use statrs::distribution::{Binomial, DiscreteCDF};
use thiserror::Error;

/// What the gate asks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GateOptions {
    /// The success probability a spec must be shown to reach (in (0, 1)).
    pub min_success: f64,
    /// The confidence of each look (in (0, 1)).
    pub confidence: f64,
    /// Trials after which the gate stops undecided (at least 1).
    pub max_trials: usize,
}

impl Default for GateOptions {
    /// P = 0.99 and C = 0.95: a deployment should succeed 99 times in 100, shown at the
    /// confidence usual for engineering tests. At most 2,000 trials, chosen from the exact
    /// characteristic at 500, 1,000, 1,500, 2,000 and 3,000: a spec failing 2 % of its trials
    /// fails 73.6, 91.6, 97.2, 98.9 and 99.6 % of its gates; 0.1 % passes 92.5 % at 500 and
    /// 99.3–99.45 % from 1,000 on; more trials only decide more of the specs near 1 %.
    fn default() -> Self {
        GateOptions {
            min_success: 0.99,
            confidence: 0.95,
            max_trials: 2000,
        }
    }
}

/// A gate that cannot be built.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum GateError {
    /// A probability outside (0, 1).
    #[error("{name} must be between 0 and 1 (exclusive), not {value}")]
    Probability {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// No trials allowed.
    #[error("the gate needs at least one trial")]
    NoTrials,
}

/// The gate's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Decision {
    /// Shown to succeed with at least the asked probability.
    Passes,
    /// Shown to succeed with less.
    Fails,
    /// Neither, within the trials allowed.
    Undecided,
}

impl Decision {
    /// The decision in words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Decision::Passes => "passes",
            Decision::Fails => "fails",
            Decision::Undecided => "undecided",
        }
    }
}

/// What a gate asked and what it decided, as reports record it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GateVerdict {
    /// What it asked.
    #[serde(flatten)]
    pub options: GateOptions,
    /// Its decision (`None`: interrupted before it decided).
    pub decision: Option<Decision>,
}

/// The gate's boundaries for every trial count up to its maximum.
#[derive(Debug, Clone, PartialEq)]
pub struct Gate {
    options: GateOptions,
    /// For n trials (index n − 1): the most failures that pass, if any do.
    pass_at_most: Vec<Option<usize>>,
    /// For n trials: the fewest failures that fail.
    fail_at_least: Vec<usize>,
}

impl Gate {
    /// The gate for `options`, its boundaries computed for every trial count.
    pub fn new(options: GateOptions) -> Result<Gate, GateError> {
        for (name, value) in [
            ("--min-success", options.min_success),
            ("--confidence", options.confidence),
        ] {
            if !(value > 0.0 && value < 1.0) {
                return Err(GateError::Probability { name, value });
            }
        }
        if options.max_trials == 0 {
            return Err(GateError::NoTrials);
        }
        let q = 1.0 - options.min_success;
        let alpha = 1.0 - options.confidence;
        let mut pass_at_most = Vec::with_capacity(options.max_trials);
        let mut fail_at_least = Vec::with_capacity(options.max_trials);
        // Both boundaries only grow with n: each search starts where the last ended.
        let mut pass: Option<usize> = None;
        let mut fail = 1usize;
        for n in 1..=options.max_trials {
            let binomial = Binomial::new(q, n as u64).expect("q is in (0, 1)");
            // Passing: P(X ≤ k) ≤ α at q, the largest such k.
            let mut k = pass.map_or(0, |k| k);
            if binomial.cdf(k as u64) <= alpha {
                while k < n && binomial.cdf(k as u64 + 1) <= alpha {
                    k += 1;
                }
                pass = Some(k);
            }
            pass_at_most.push(pass);
            // Failing: P(X ≥ k) < α at q, i.e. P(X ≤ k − 1) > 1 − α, the smallest such k.
            while fail <= n && binomial.cdf(fail as u64 - 1) <= 1.0 - alpha {
                fail += 1;
            }
            fail_at_least.push(fail);
        }
        Ok(Gate {
            options,
            pass_at_most,
            fail_at_least,
        })
    }

    /// What the gate asks.
    pub fn options(&self) -> &GateOptions {
        &self.options
    }

    /// The decision after `trials` trials of which `failed` failed: `Some` once a boundary is
    /// reached (or, undecided, once the trials are used up), `None` while it goes on.
    pub fn decide(&self, trials: usize, failed: usize) -> Option<Decision> {
        if trials == 0 {
            return None;
        }
        let i = trials.min(self.options.max_trials) - 1;
        if failed >= self.fail_at_least[i] {
            Some(Decision::Fails)
        } else if self.pass_at_most[i].is_some_and(|k| failed <= k) {
            Some(Decision::Passes)
        } else if trials >= self.options.max_trials {
            Some(Decision::Undecided)
        } else {
            None
        }
    }

    /// Whether a spec with `failed` failures so far can still pass within the gate's trials
    /// (a search that keeps only what passes may stop once it cannot).
    pub fn can_still_pass(&self, failed: usize) -> bool {
        self.pass_at_most
            .last()
            .copied()
            .flatten()
            .is_some_and(|k| failed <= k)
    }

    /// The trials a spec that never fails needs to pass.
    pub fn trials_to_pass_without_failure(&self) -> Option<usize> {
        self.pass_at_most
            .iter()
            .position(Option::is_some)
            .map(|i| i + 1)
    }

    /// Judges outcomes (true: the trial passed) in order until a decision: the decision and
    /// the trials it took. Outcomes left after the decision are not read; running out of
    /// outcomes before one is `None` (more trials are needed).
    pub fn judge(&self, outcomes: impl IntoIterator<Item = bool>) -> Option<(Decision, usize)> {
        let mut failed = 0;
        for (i, passed) in outcomes.into_iter().enumerate() {
            failed += usize::from(!passed);
            if let Some(d) = self.decide(i + 1, failed) {
                return Some((d, i + 1));
            }
        }
        None
    }

    /// How the gate decides for a spec whose trials fail independently with probability
    /// `failure_rate`, computed exactly.
    pub fn operating_characteristic(&self, failure_rate: f64) -> OperatingPoint {
        let q = failure_rate.clamp(0.0, 1.0);
        let mut point = OperatingPoint {
            failure_rate: q,
            passes: 0.0,
            fails: 0.0,
            undecided: 0.0,
            expected_trials: 0.0,
        };
        // Probability of each failure count among the runs still going.
        let mut alive = vec![1.0];
        for n in 1..=self.options.max_trials {
            point.expected_trials += alive.iter().sum::<f64>();
            let mut next = vec![0.0; alive.len() + 1];
            for (k, p) in alive.iter().enumerate() {
                next[k] += p * (1.0 - q);
                next[k + 1] += p * q;
            }
            for (k, p) in next.iter_mut().enumerate() {
                match self.decide(n, k) {
                    Some(Decision::Passes) => point.passes += *p,
                    Some(Decision::Fails) => point.fails += *p,
                    Some(Decision::Undecided) => point.undecided += *p,
                    None => continue,
                }
                *p = 0.0;
            }
            while next.last() == Some(&0.0) && next.len() > 1 {
                next.pop();
            }
            alive = next;
        }
        point
    }
}

/// How often the gate passes, fails and stays undecided for one failure probability, and the
/// trials it takes on average.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OperatingPoint {
    /// The failure probability of every trial.
    pub failure_rate: f64,
    /// Probability that the gate passes.
    pub passes: f64,
    /// Probability that it fails.
    pub fails: f64,
    /// Probability that it stops undecided.
    pub undecided: f64,
    /// Mean number of trials it runs.
    pub expected_trials: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn gate() -> Gate {
        Gate::new(GateOptions::default()).unwrap()
    }

    /// The properties the deployment gate promises (issue 20), on its exact operating
    /// characteristic.
    #[test]
    fn the_default_gate_keeps_its_promises() {
        let g = gate();
        let rare = g.operating_characteristic(0.001);
        assert!(rare.passes >= 0.95, "{rare:?}");
        let often = g.operating_characteristic(0.02);
        assert!(often.fails >= 0.95, "{often:?}");
        let always = g.operating_characteristic(1.0);
        assert_eq!(always.fails, 1.0);
        assert!(always.expected_trials <= 10.0, "{always:?}");
        let never = g.operating_characteristic(0.0);
        assert_eq!(never.passes, 1.0);
        assert!(never.expected_trials <= 300.0, "{never:?}");
        assert_eq!(g.trials_to_pass_without_failure(), Some(299));
        for p in [rare, often, always, never] {
            assert!(
                (p.passes + p.fails + p.undecided - 1.0).abs() < 1e-9,
                "{p:?}"
            );
        }
    }

    /// The exact characteristic agrees with 100,000 simulated gates (a check of the walk).
    #[test]
    fn simulated_gates_agree_with_the_exact_characteristic() {
        let g = gate();
        let q = 0.008;
        let exact = g.operating_characteristic(q);
        let mut rng = ChaCha8Rng::seed_from_u64(20);
        let runs = 100_000;
        let mut counts = [0usize; 3];
        let mut trials = 0usize;
        for _ in 0..runs {
            let (d, n) = g
                .judge(std::iter::repeat_with(|| rng.gen::<f64>() >= q))
                .unwrap();
            trials += n;
            counts[d as usize] += 1;
        }
        let share = |c: usize| c as f64 / runs as f64;
        // Four binomial standard errors at most.
        let close =
            |sim: f64, p: f64| (sim - p).abs() <= 4.0 * (p * (1.0 - p) / runs as f64).sqrt() + 1e-9;
        assert!(
            close(share(counts[0]), exact.passes),
            "{counts:?} {exact:?}"
        );
        assert!(close(share(counts[1]), exact.fails), "{counts:?} {exact:?}");
        let mean = trials as f64 / runs as f64;
        assert!(
            (mean - exact.expected_trials).abs() / exact.expected_trials < 0.02,
            "{mean} {exact:?}"
        );
    }

    #[test]
    fn a_spec_cannot_pass_once_its_failures_exceed_the_last_boundary() {
        let g = gate();
        let last = (0..100)
            .take_while(|&k| g.can_still_pass(k))
            .last()
            .unwrap();
        assert_eq!(g.decide(2000, last), Some(Decision::Passes));
        assert_ne!(g.decide(2000, last + 1), Some(Decision::Passes));
        for n in 1..=2000 {
            assert_ne!(g.decide(n, last + 1), Some(Decision::Passes), "{n}");
        }
    }

    #[test]
    fn the_boundaries_are_those_of_the_one_sided_intervals() {
        let g = gate();
        // No failure: the upper bound 1 − 0.05^(1/n) reaches 1 % at n = 299.
        assert_eq!(g.decide(298, 0), None);
        assert_eq!(g.decide(299, 0), Some(Decision::Passes));
        // One failure in the first trial: the lower bound 0.05 exceeds 1 %.
        assert_eq!(g.decide(1, 1), Some(Decision::Fails));
        // One failure in 10: the lower bound is 0.51 %, undecided.
        assert_eq!(g.decide(10, 1), None);
        assert_eq!(g.judge([true; 5]), None);
        assert_eq!(
            g.judge(std::iter::repeat(true)),
            Some((Decision::Passes, 299))
        );
        let short = Gate::new(GateOptions {
            max_trials: 50,
            ..GateOptions::default()
        })
        .unwrap();
        assert_eq!(
            short.judge(std::iter::repeat(true)),
            Some((Decision::Undecided, 50))
        );
    }

    #[test]
    fn impossible_options_are_refused() {
        for (min_success, confidence, max_trials) in
            [(1.0, 0.95, 10), (0.9, 0.0, 10), (0.9, 0.9, 0)]
        {
            let e = Gate::new(GateOptions {
                min_success,
                confidence,
                max_trials,
            });
            assert!(e.is_err());
        }
    }
}
