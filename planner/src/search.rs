//! Using the freedom a spec gives: plan several whole-spec candidates and keep the quickest.
//!
//! Candidate 0 is the nominal-first plan (every keyframe on its TSR's nominal pose when
//! reachable, `GoalStrategy::Nominal`), the plan a budget of one candidate gives. Every
//! further candidate spreads its goals across each keyframe's TSR and across IK branches,
//! quickest to reach first (`GoalStrategy::Spread`), with its own seed, so candidates differ in
//! the poses drawn, the branches found and the paths searched. The plan kept is the one with
//! the shortest execution time (ties: the earlier candidate), so a budget never gives a
//! slower plan than a single candidate with the same seed.
//!
//! Candidates are whole specs, not windows of keyframes: one costs a few milliseconds per
//! keyframe (see [`MS_PER_KEYFRAME`]), so a budget of a few hundred milliseconds buys tens of
//! whole-spec evaluations, and the cost it minimizes is the one the robot pays.
//!
//! The budget is a number of candidates, never a wall-clock limit: the same seed and budget
//! give the same plan on any machine, however loaded.

use crate::error::PlanError;
use crate::goal::GoalStrategy;
use crate::plan::Plan;
use crate::robot::Robot;
use crate::task::{plan_candidate, PlanOptions};
use akl_scene::World;
use akl_tsr::TaskSpec;

/// Milliseconds one spread candidate takes per keyframe on the reference machine (BENCHMARKS.md,
/// "Planning budget"): the calibration that turns `--budget MS` into a candidate count.
///
/// Measured as the mean planning time of spread candidates of the three ground truths,
/// divided by their keyframe counts (`cargo bench -p akl-planner --bench budget`).
pub const MS_PER_KEYFRAME: f64 = 2.5;

/// How many whole-spec candidates [`plan_best`] plans.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanBudget {
    /// Candidates planned (at least one).
    pub candidates: usize,
}

impl PlanBudget {
    /// One candidate: the nominal-first plan.
    pub const SINGLE: PlanBudget = PlanBudget { candidates: 1 };

    /// A budget of `candidates` candidates (at least one).
    pub fn candidates(candidates: usize) -> PlanBudget {
        PlanBudget {
            candidates: candidates.max(1),
        }
    }

    /// The candidates `ms` milliseconds of planning buy for a spec of `keyframes` keyframes on
    /// the reference machine: one, plus one per [`MS_PER_KEYFRAME`] × `keyframes` ms. A fixed
    /// conversion, so the plan never depends on how fast this machine happens to be.
    pub fn from_millis(ms: u64, keyframes: usize) -> PlanBudget {
        let per_candidate = MS_PER_KEYFRAME * keyframes.max(1) as f64;
        PlanBudget::candidates(1 + (ms as f64 / per_candidate).floor() as usize)
    }
}

impl Default for PlanBudget {
    fn default() -> Self {
        PlanBudget::SINGLE
    }
}

/// What one candidate gave.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateOutcome {
    /// How its goals were chosen.
    pub strategy: GoalStrategy,
    /// The seed it was planned with.
    pub seed: u64,
    /// Its execution time (seconds), or why it failed.
    pub result: Result<f64, PlanError>,
}

/// The plan kept and what every candidate gave.
#[derive(Debug, Clone, PartialEq)]
pub struct BestPlan {
    /// The quickest plan found.
    pub plan: Plan,
    /// Its index among `candidates`.
    pub chosen: usize,
    /// Every candidate, in the order planned.
    pub candidates: Vec<CandidateOutcome>,
}

impl BestPlan {
    /// Execution time of the nominal-first candidate (candidate 0), if it planned.
    pub fn nominal_duration(&self) -> Option<f64> {
        self.candidates
            .first()
            .and_then(|c| c.result.as_ref().ok().copied())
    }
}

/// The seed of candidate `k`: the caller's for candidate 0, a SplitMix64 scramble of it and `k`
/// for the others (distinct, well-spread streams).
fn candidate_seed(seed: u64, k: usize) -> u64 {
    if k == 0 {
        return seed;
    }
    let mut z = seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Plans `options.budget.candidates` whole-spec candidates and keeps the quickest. Fails only
/// if every candidate fails, with candidate 0's error (the nominal-first plan's reason).
pub fn plan_best(
    robot: &Robot,
    spec: &TaskSpec,
    world: &World,
    options: &PlanOptions,
) -> Result<BestPlan, PlanError> {
    let count = options.budget.candidates.max(1);
    let mut best: Option<(usize, Plan)> = None;
    let mut candidates = Vec::with_capacity(count);
    for k in 0..count {
        let mut candidate = options.clone();
        candidate.seed = candidate_seed(options.seed, k);
        candidate.goals.strategy = if k == 0 {
            options.goals.strategy
        } else {
            GoalStrategy::Spread
        };
        let result = plan_candidate(robot, spec, world, &candidate);
        candidates.push(CandidateOutcome {
            strategy: candidate.goals.strategy,
            seed: candidate.seed,
            result: result.as_ref().map(|p| p.duration).map_err(Clone::clone),
        });
        if let Ok(plan) = result {
            if best.as_ref().is_none_or(|(_, b)| plan.duration < b.duration) {
                best = Some((k, plan));
            }
        }
    }
    let Some((chosen, mut plan)) = best else {
        return Err(first_error(candidates));
    };
    plan.seed = options.seed;
    Ok(BestPlan {
        plan,
        chosen,
        candidates,
    })
}

/// The error of the first failed candidate (candidate 0 when none planned).
fn first_error(candidates: Vec<CandidateOutcome>) -> PlanError {
    candidates
        .into_iter()
        .find_map(|c| c.result.err())
        .unwrap_or_else(|| PlanError::Grounding("no candidate was planned".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_budget_in_milliseconds_is_a_fixed_candidate_count() {
        assert_eq!(PlanBudget::from_millis(0, 4), PlanBudget::SINGLE);
        let per = MS_PER_KEYFRAME * 4.0;
        assert_eq!(PlanBudget::from_millis(per as u64, 4).candidates, 2);
        assert_eq!(
            PlanBudget::from_millis((10.0 * per) as u64, 4).candidates,
            11
        );
        assert_eq!(PlanBudget::candidates(0), PlanBudget::SINGLE);
    }

    #[test]
    fn candidate_seeds_differ_and_keep_the_first() {
        assert_eq!(candidate_seed(7, 0), 7);
        let seeds: std::collections::BTreeSet<u64> =
            (0..100).map(|k| candidate_seed(7, k)).collect();
        assert_eq!(seeds.len(), 100);
    }
}
