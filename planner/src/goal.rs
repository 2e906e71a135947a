//! TSR goals: poses drawn from a keyframe's grounded TSR (the nominal pose first), solved by
//! inverse kinematics, kept when a caller's test (collision, approach, look-ahead) accepts
//! them, nearest the current configuration first.

use crate::robot::Robot;
use akl_tsr::{Pose, Tsr};
use rand::Rng;
use std::collections::BTreeMap;

/// How hard to look for goal configurations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GoalOptions {
    /// Poses drawn from the TSR at most (the nominal pose counts as one).
    pub poses: usize,
    /// Distinct IK solutions tried per pose.
    pub solutions_per_pose: usize,
    /// Accepted candidates after which the search stops.
    pub enough: usize,
}

impl Default for GoalOptions {
    fn default() -> Self {
        GoalOptions {
            poses: 30,
            solutions_per_pose: 6,
            enough: 4,
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
/// configuration. If the nominal pose yields an accepted configuration, only the nominal
/// pose's candidates are returned (they are exactly on target); otherwise poses are drawn
/// until `enough` candidates are found. Candidates come nearest `seed` first.
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
    for (k, pose) in poses.iter().enumerate() {
        tried += 1;
        let target = base_inv * pose;
        for q in robot.ik_solutions(&target, seed, options.solutions_per_pose) {
            solutions += 1;
            match accept(pose, &q) {
                Ok(data) => found.push(Candidate {
                    pose: *pose,
                    q,
                    data,
                }),
                Err(reason) => *reasons.entry(reason).or_default() += 1,
            }
        }
        if (k == 0 && !found.is_empty()) || found.len() >= options.enough {
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
    let distance = |q: &[f64]| crate::space::distance(q, seed);
    found.sort_by(|a, b| distance(&a.q).total_cmp(&distance(&b.q)));
    Ok(found)
}
