//! TSR goals: poses drawn from a keyframe's grounded TSR, solved by inverse kinematics, kept
//! when a caller's test (collision, approach, look-ahead) accepts them.
//!
//! Two strategies ([`GoalStrategy`]): `Nominal` stays on the TSR's nominal pose whenever it is
//! reachable (the spec's demonstrated pose, exactly on target), nearest the current
//! configuration first; `Spread` draws poses across the whole region and keeps every IK branch
//! it finds, quickest to reach first, so that a wider TSR gives the planner more to choose
//! from.

use crate::robot::Robot;
use crate::timing;
use akl_tsr::{Pose, Tsr};
use rand::Rng;
use std::collections::BTreeMap;

/// Which goals a search returns, and in which order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GoalStrategy {
    /// The nominal pose first; when it has an accepted solution only its solutions are
    /// returned; nearest the current configuration (joint-space distance) first.
    #[default]
    Nominal,
    /// Poses drawn across the region (the nominal among them), `enough` at a time, and every IK
    /// branch found for each, tried and returned quickest to reach from the current
    /// configuration first (the rest-to-rest time of the straight joint-space move, within the velocity and
    /// acceleration limits).
    Spread,
}

/// How hard to look for goal configurations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GoalOptions {
    /// Poses drawn from the TSR at most (the nominal pose counts as one).
    pub poses: usize,
    /// Distinct IK solutions tried per pose.
    pub solutions_per_pose: usize,
    /// Accepted candidates after which the search stops (with `Spread`, also the poses drawn
    /// at a time).
    pub enough: usize,
    /// Nominal-first or spread across the region.
    pub strategy: GoalStrategy,
}

impl Default for GoalOptions {
    fn default() -> Self {
        GoalOptions {
            poses: 30,
            solutions_per_pose: 6,
            enough: 4,
            strategy: GoalStrategy::Nominal,
        }
    }
}

/// An accepted goal: the TCP pose, its configuration, and what the caller's test returned.
#[derive(Debug, Clone)]
pub struct Candidate<T> {
    /// TCP pose in the world.
    pub pose: Pose,
    /// Arm configuration reaching it.
    pub q: Vec<f64>,
    /// The caller's data (e.g. the approach path).
    pub data: T,
}

/// Why no goal was found.
#[derive(Debug, Clone, PartialEq)]
pub enum GoalFailure {
    /// No pose tried had an IK solution.
    Unreachable {
        /// Poses tried.
        tried: usize,
    },
    /// Solutions existed but the test rejected them all.
    Rejected {
        /// Poses tried.
        tried: usize,
        /// Solutions rejected.
        solutions: usize,
        /// The most frequent reason.
        blocker: Option<String>,
    },
}

/// The poses to try: the TSR's nominal pose (or the nearest member, when the bounds exclude
/// it), then uniform samples.
pub fn tsr_poses<R: Rng + ?Sized>(tsr: &Tsr, count: usize, rng: &mut R) -> Vec<Pose> {
    let nominal = tsr.nominal();
    let first = if tsr.contains(&nominal) {
        nominal
    } else {
        tsr.closest(&nominal)
    };
    let mut poses = vec![first];
    while poses.len() < count {
        poses.push(tsr.sample(rng));
    }
    poses
}

/// Searches goal configurations for `tsr` (world frame); `base` is the robot base pose,
/// `seed` the current configuration. `accept` returns the caller's data or why it rejects a
/// configuration. With [`GoalStrategy::Nominal`], if the nominal pose yields an accepted
/// configuration only the nominal pose's candidates are returned (they are exactly on
/// target), otherwise poses are drawn until `enough` candidates are found, nearest `seed`
/// first. With [`GoalStrategy::Spread`] poses are drawn `enough` at a time and their IK
/// branches tried quickest to reach from `seed` first, until `enough` candidates are found,
/// quickest first.
pub fn find_goals<T, R: Rng + ?Sized>(
    robot: &Robot,
    tsr: &Tsr,
    base: &Pose,
    seed: &[f64],
    options: &GoalOptions,
    rng: &mut R,
    mut accept: impl FnMut(&Pose, &[f64]) -> Result<T, String>,
) -> Result<Vec<Candidate<T>>, GoalFailure> {
    let poses = tsr_poses(tsr, options.poses, rng);
    let base_inv = base.inverse();
    let mut found: Vec<Candidate<T>> = Vec::new();
    let mut solutions = 0;
    let mut reasons: BTreeMap<String, usize> = BTreeMap::new();
    let mut tried = 0;
    // Nominal: one pose at a time. Spread: `enough` poses at a time, their IK branches tried
    // quickest first, so the accept test (the costly part) runs on the best branches only.
    let chunk = match options.strategy {
        GoalStrategy::Nominal => 1,
        GoalStrategy::Spread => options.enough.max(1),
    };
    for (c, group) in poses.chunks(chunk).enumerate() {
        tried += group.len();
        let mut branches: Vec<(Pose, Vec<f64>)> = Vec::new();
        for pose in group {
            let target = base_inv * pose;
            for q in robot.ik_solutions(&target, seed, options.solutions_per_pose) {
                branches.push((*pose, q));
            }
        }
        if options.strategy == GoalStrategy::Spread {
            let mut timed: Vec<(f64, (Pose, Vec<f64>))> = branches
                .into_iter()
                .map(|b| (move_time(robot, seed, &b.1), b))
                .collect();
            timed.sort_by(|a, b| a.0.total_cmp(&b.0));
            branches = timed.into_iter().map(|(_, b)| b).collect();
        }
        for (pose, q) in branches {
            if options.strategy == GoalStrategy::Spread && found.len() >= options.enough {
                break;
            }
            solutions += 1;
            match accept(&pose, &q) {
                Ok(data) => found.push(Candidate { pose, q, data }),
                Err(reason) => *reasons.entry(reason).or_default() += 1,
            }
        }
        let nominal_done = options.strategy == GoalStrategy::Nominal && c == 0;
        if (nominal_done && !found.is_empty()) || found.len() >= options.enough {
            break;
        }
    }
    if found.is_empty() {
        if solutions == 0 {
            return Err(GoalFailure::Unreachable { tried });
        }
        let blocker = reasons.into_iter().max_by_key(|(_, n)| *n).map(|(r, _)| r);
        return Err(GoalFailure::Rejected {
            tried,
            solutions,
            blocker,
        });
    }
    match options.strategy {
        GoalStrategy::Nominal => {
            let distance = |q: &[f64]| crate::space::distance(q, seed);
            found.sort_by(|a, b| distance(&a.q).total_cmp(&distance(&b.q)));
        }
        GoalStrategy::Spread => {
            let time = |q: &[f64]| move_time(robot, seed, q);
            found.sort_by(|a, b| time(&a.q).total_cmp(&time(&b.q)));
        }
    }
    Ok(found)
}

/// Seconds of the fastest rest-to-rest straight joint-space move from `a` to `b`: a lower
/// bound on any motion between them, used to rank goals.
pub fn move_time(robot: &Robot, a: &[f64], b: &[f64]) -> f64 {
    timing::linear(
        &[a.to_vec(), b.to_vec()],
        robot.velocity_limits(),
        robot.acceleration_limits(),
    )
    .duration()
}
