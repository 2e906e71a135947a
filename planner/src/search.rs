//! Using the freedom a spec gives: plan several whole-spec candidates and keep the quickest.
//!
//! Candidate 0 is the nominal-first plan (every keyframe on its TSR's nominal pose when
//! reachable, `GoalStrategy::Nominal`), the plan a budget of one candidate gives. Every
//! further candidate spreads its goals across each keyframe's TSR and across IK branches,
//! quickest to reach first (`GoalStrategy::Spread`), with its own seed, so candidates differ in
//! the poses drawn, the branches found and the paths searched. The plan kept is the one with
//! the shortest execution time (ties: the earlier candidate), so a budget never gives a
//! slower plan than a single candidate with the same seed. A spread candidate reaches a
//! `move_in_line` keyframe by the quickest of the lines it plans to poses of that keyframe's
//! TSR; only when the line is planned ahead from the previous keyframe's goals (to check that
//! a goal can start it) does its end stay nominal-first: drawing that end across the region
//! too was measured slower on inspection (median wide / truth 1.000 instead of 0.988).
//!
//! Candidates are whole specs, not windows of keyframes: one costs a few milliseconds per
//! keyframe (see [`crate::options::MS_PER_KEYFRAME`]), so a budget of a few hundred milliseconds buys tens of
//! whole-spec evaluations, and the cost it minimizes is the one the robot pays.
//!
//! Verification plans differently: with `GoalStrategy::Sampled` every candidate draws its goals
//! at random within the regions and the first candidate that plans is kept (see [`plan_best`]).
//!
//! The budget is a number of candidates, never a wall-clock limit: the same seed and budget
//! give the same plan on any machine, however loaded.

use crate::error::PlanError;
use crate::goal::GoalStrategy;
use crate::options::PlanOptions;
use crate::plan::Plan;
use crate::robot::Robot;
use crate::task::plan_candidate;
use akl_scene::World;
use akl_tsr::TaskSpec;
use std::cell::Cell;

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
    /// Configurations probed for collisions over every candidate: how much checking the plan
    /// took, the same on any machine (unlike its time), so that a spec whose regions are
    /// mostly poses the planner must reject shows as costly.
    pub probes: u64,
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

/// Plans `spec` for `robot` in `world`: one timed joint trajectory with gripper events, the
/// quickest of the candidates `options.budget` allows (see [`plan_best`]).
/// Errors name the keyframe or segment and the reason.
pub fn plan_task(
    robot: &Robot,
    spec: &TaskSpec,
    world: &World,
    options: &PlanOptions,
) -> Result<Plan, PlanError> {
    plan_best(robot, spec, world, options).map(|best| best.plan)
}

/// Plans `options.budget.candidates` whole-spec candidates and keeps the quickest. Fails only
/// if every candidate fails, with candidate 0's error (the nominal-first plan's reason).
///
/// With [`GoalStrategy::Sampled`] (verification) every candidate draws its goals at random and
/// the first that plans is kept, not the quickest: a draw that leads nowhere (a grasp taken so
/// high on an object that no pose of the release region clears the support) is drawn again,
/// as a planner searching the regions would, while the plan kept stays a random draw.
pub fn plan_best(
    robot: &Robot,
    spec: &TaskSpec,
    world: &World,
    options: &PlanOptions,
) -> Result<BestPlan, PlanError> {
    options.check()?;
    let count = options.budget.candidates.max(1);
    let mut best: Option<(usize, Plan)> = None;
    let mut candidates = Vec::with_capacity(count);
    let probes = Cell::new(0);
    for k in 0..count {
        let mut candidate = options.clone();
        candidate.seed = candidate_seed(options.seed, k);
        candidate.goals.strategy = match options.goals.strategy {
            GoalStrategy::Sampled => GoalStrategy::Sampled,
            first if k == 0 => first,
            _ => GoalStrategy::Spread,
        };
        let result = plan_candidate(robot, spec, world, &candidate, &probes);
        candidates.push(CandidateOutcome {
            strategy: candidate.goals.strategy,
            seed: candidate.seed,
            result: result.as_ref().map(|p| p.duration).map_err(Clone::clone),
        });
        if let Ok(plan) = result {
            if best
                .as_ref()
                .is_none_or(|(_, b)| plan.duration < b.duration)
            {
                best = Some((k, plan));
            }
        }
        if options.goals.strategy == GoalStrategy::Sampled && best.is_some() {
            break;
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
        probes: probes.get(),
    })
}

/// The error of the first failed candidate (candidate 0 when none planned).
fn first_error(candidates: Vec<CandidateOutcome>) -> PlanError {
    candidates
        .into_iter()
        .find_map(|c| c.result.err())
        .unwrap_or(PlanError::NoCandidate)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::{recheck, RecheckOptions};
    use crate::options::PlanBudget;
    use akl_scene::builtin;
    use akl_tsr::Bounds;

    /// The pick_place truth with every TSR widened to ±3 cm and ±0.4 rad of yaw.
    fn widened(spec: &TaskSpec) -> TaskSpec {
        let mut wide = spec.clone();
        for k in &mut wide.keyframes {
            let mut bw = Bounds::symmetric(0.03, 0.05);
            bw.0[5] = [-0.4, 0.4];
            k.tsr.bw = bw;
        }
        wide
    }

    #[test]
    fn a_budget_keeps_the_quickest_sound_plan_and_never_a_slower_one() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("pick_place").unwrap().unwrap();
        let wide = widened(task.truth.as_ref().unwrap());
        let options = PlanOptions {
            seed: 3,
            budget: PlanBudget::candidates(6),
            ..PlanOptions::default()
        };
        let best = plan_best(&robot, &wide, &task.world, &options).unwrap();
        assert_eq!(best.candidates.len(), 6);
        assert_eq!(best.candidates[0].strategy, GoalStrategy::Nominal);
        assert!(best.candidates[1..]
            .iter()
            .all(|c| c.strategy == GoalStrategy::Spread));
        let durations: Vec<f64> = best
            .candidates
            .iter()
            .filter_map(|c| c.result.as_ref().ok().copied())
            .collect();
        assert!(durations.len() >= 2, "{:?}", best.candidates);
        let fastest = durations.iter().copied().fold(f64::INFINITY, f64::min);
        assert_eq!(best.plan.duration, fastest);
        assert!(best.plan.duration <= best.nominal_duration().unwrap());
        assert!(
            durations.iter().any(|d| *d != durations[0]),
            "spread candidates should differ from the nominal one: {durations:?}"
        );
        let violations = recheck(&robot, &task.world, &best.plan, &RecheckOptions::default());
        assert!(violations.is_empty(), "{}", violations[0]);
        // Every grasp and release of the kept plan lies within its (grounded) keyframe TSR.
        let grounded = wide.ground(&task.world.object_poses()).unwrap();
        for event in best.plan.events.iter().filter(|e| e.keyframe == 0) {
            let q = best.plan.sample(event.t);
            let tcp = task.world.robot_base * robot.tcp_pose(&q);
            assert!(grounded.keyframes[0].tsr.contains(&tcp));
        }
        let again = plan_best(&robot, &wide, &task.world, &options).unwrap();
        assert_eq!(again.plan.duration, best.plan.duration);
        assert_eq!(again.chosen, best.chosen);
    }

    #[test]
    fn when_every_candidate_fails_the_nominal_reason_is_reported() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("inspection").unwrap().unwrap();
        let mut far = task.truth.clone().unwrap();
        far.keyframes[3].tsr.tw_e.translation.vector.x += 2.0;
        let options = PlanOptions {
            budget: PlanBudget::candidates(3),
            ..PlanOptions::default()
        };
        let e = plan_best(&robot, &far, &task.world, &options).unwrap_err();
        assert!(
            matches!(e, PlanError::Unreachable { keyframe: 3, .. }),
            "{e}"
        );
    }

    #[test]
    fn a_budget_in_milliseconds_is_a_fixed_candidate_count() {
        assert_eq!(PlanBudget::from_millis(0, 4), PlanBudget::SINGLE);
        // 3.8 ms x 4 keyframes = 15.2 ms a candidate.
        assert_eq!(PlanBudget::from_millis(15, 4).candidates, 1);
        assert_eq!(PlanBudget::from_millis(16, 4).candidates, 2);
        assert_eq!(PlanBudget::from_millis(151, 4).candidates, 10);
        assert_eq!(PlanBudget::from_millis(153, 4).candidates, 11);
        assert_eq!(PlanBudget::from_millis(200, 0).candidates, 53);
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
