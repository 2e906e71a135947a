//! TSR goals: poses drawn from a keyframe's grounded TSR, solved by inverse kinematics, kept
//! when a caller's test (collision, approach, look-ahead) accepts them.
//!
//! Three strategies ([`GoalStrategy`]): `Nominal` stays on the TSR's nominal pose whenever it
//! is reachable (the spec's demonstrated pose, exactly on target), nearest the current
//! configuration first; `Spread` draws poses across the whole region and keeps every IK branch
//! it finds, quickest to reach first, so that a wider TSR gives the planner more to choose
//! from; `Sampled` goes to a pose drawn at random within the region, the nominal not
//! preferred, so that verification tries the whole region rather than its centre.

use crate::robot::Robot;
use crate::timing;
use akl_tsr::{Keyframe, Pose, Tsr};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
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
    /// Poses drawn uniformly within the region (the nominal pose not among them, from the
    /// keyframe's own stream, [`keyframe_stream`]), tried one at a time in the order drawn: the
    /// goal is the first pose with an accepted configuration (its solutions nearest the
    /// current configuration first), the end of a line the first drawn pose the line reaches. A trial's goal is then a random member of the TSR (of the
    /// part the arm can use), which is what verifying a TSR's width needs: with `Nominal`
    /// goals a wider TSR never changes the plan, so a trial would say nothing of the poses
    /// the spec newly allows. `akl validate` and `akl relax` plan their trials this way. (The
    /// planner may move a drawn grasp or release within its region before it is solved, to
    /// where the hand and the held object fit: `find_fitted_goals`.)
    Sampled,
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
    /// Nominal-first, spread across the region, or sampled within it (for verification).
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
pub(crate) struct Candidate<T> {
    /// TCP pose in the world.
    pub pose: Pose,
    /// Arm configuration reaching it.
    pub q: Vec<f64>,
    /// The caller's data (e.g. the approach path).
    pub data: T,
}

/// Why no goal was found.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum GoalFailure {
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
/// it), then uniform samples; with [`GoalStrategy::Sampled`], uniform samples only.
pub(crate) fn tsr_poses<R: Rng + ?Sized>(
    tsr: &Tsr,
    count: usize,
    strategy: GoalStrategy,
    rng: &mut R,
) -> Vec<Pose> {
    let mut poses = Vec::with_capacity(count);
    if strategy != GoalStrategy::Sampled {
        let nominal = tsr.nominal();
        poses.push(if tsr.contains(&nominal) {
            nominal
        } else {
            tsr.closest(&nominal)
        });
    }
    while poses.len() < count {
        poses.push(tsr.sample(rng));
    }
    poses
}

/// The random stream a keyframe's [`GoalStrategy::Sampled`] goals are drawn from in a plan
/// seeded `seed`. It depends on the seed and on the keyframe's region (reference, offset,
/// bounds; not where its reference happens to stand), never on the keyframe's place in the
/// spec, its gripper or the line into it: a region draws the same goals in every spec that
/// has it, so a spec and the same spec without another keyframe, or without a line, are
/// compared on the same goals (common random numbers), and a difference between their
/// trials is the removal's doing.
pub fn keyframe_stream(seed: u64, kf: &Keyframe) -> ChaCha8Rng {
    // FNV-1a over the keyframe's words: stable across builds and platforms, unlike std's
    // hasher; ChaCha whitens the result.
    let mut h = 0xcbf2_9ce4_8422_2325_u64 ^ seed;
    let mut eat = |word: u64| h = (h ^ word).wrapping_mul(0x0000_0100_0000_01b3);
    kf.reference.bytes().for_each(|b| eat(u64::from(b)));
    let tw_e = &kf.tsr.tw_e;
    tw_e.translation
        .vector
        .iter()
        .chain(tw_e.rotation.coords.iter())
        .chain(kf.tsr.bw.0.iter().flatten())
        .for_each(|v| eat(v.to_bits()));
    ChaCha8Rng::seed_from_u64(h)
}

/// Searches goal configurations for `tsr` (world frame); `base` is the robot base pose,
/// `seed` the current configuration. `accept` returns the caller's data or why it rejects a
/// configuration. With [`GoalStrategy::Nominal`], if the nominal pose yields an accepted
/// configuration only the nominal pose's candidates are returned (they are exactly on
/// target), otherwise poses are drawn until `enough` candidates are found, nearest `seed`
/// first. With [`GoalStrategy::Spread`] poses are drawn `enough` at a time and their IK
/// branches tried quickest to reach from `seed` first, until `enough` candidates are found,
/// quickest first. With [`GoalStrategy::Sampled`] only the candidates of the first drawn pose
/// that yields any are returned, nearest `seed` first. (The planner fits its poses: it calls
/// `find_fitted_goals`; the tests call this.)
#[cfg(test)]
pub(crate) fn find_goals<T, R: Rng + ?Sized>(
    robot: &Robot,
    tsr: &Tsr,
    base: &Pose,
    seed: &[f64],
    options: &GoalOptions,
    rng: &mut R,
    accept: impl FnMut(&Pose, &[f64]) -> Result<T, String>,
) -> Result<Vec<Candidate<T>>, GoalFailure> {
    find_fitted_goals(robot, tsr, base, seed, options, rng, |p| *p, accept)
}

/// `find_goals` with each pose moved by `fit` before inverse kinematics: the caller moves a
/// drawn pose (within the region) to where it can be used, or returns it as it is (the
/// planner's grasps and releases, see `task::fit`). Each pose is fitted once, when its turn
/// comes, so poses never tried cost nothing.
#[allow(clippy::too_many_arguments)]
pub(crate) fn find_fitted_goals<T, R: Rng + ?Sized>(
    robot: &Robot,
    tsr: &Tsr,
    base: &Pose,
    seed: &[f64],
    options: &GoalOptions,
    rng: &mut R,
    fit: impl Fn(&Pose) -> Pose,
    mut accept: impl FnMut(&Pose, &[f64]) -> Result<T, String>,
) -> Result<Vec<Candidate<T>>, GoalFailure> {
    let poses = tsr_poses(tsr, options.poses, options.strategy, rng);
    let base_inv = base.inverse();
    let mut found: Vec<Candidate<T>> = Vec::new();
    let mut solutions = 0;
    let mut reasons: BTreeMap<String, usize> = BTreeMap::new();
    let mut tried = 0;
    // Nominal and Sampled: one pose at a time. Spread: `enough` poses at a time, their IK
    // branches tried quickest first, so the accept test (the costly part) runs on the best
    // branches only.
    let chunk = match options.strategy {
        GoalStrategy::Nominal | GoalStrategy::Sampled => 1,
        GoalStrategy::Spread => options.enough.max(1),
    };
    for (c, group) in poses.chunks(chunk).enumerate() {
        tried += group.len();
        let mut branches: Vec<(Pose, Vec<f64>)> = Vec::new();
        for drawn in group {
            let pose = fit(drawn);
            let target = base_inv * pose;
            for q in robot.ik_solutions(&target, seed, options.solutions_per_pose) {
                branches.push((pose, q));
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
        let settled = !found.is_empty()
            && match options.strategy {
                GoalStrategy::Nominal => c == 0,
                GoalStrategy::Sampled => true,
                GoalStrategy::Spread => false,
            };
        if settled || found.len() >= options.enough {
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
        GoalStrategy::Nominal | GoalStrategy::Sampled => {
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
pub(crate) fn move_time(robot: &Robot, a: &[f64], b: &[f64]) -> f64 {
    timing::linear(
        &[a.to_vec(), b.to_vec()],
        robot.velocity_limits(),
        robot.acceleration_limits(),
    )
    .duration()
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::{pose_from_xyz_rpy, position_distance};
    use akl_tsr::{Bounds, Constraint, Gripper, KeyframeKind};

    /// A region ±4 cm and ±0.3 rad about a reachable pose in front of the Panda, pointing down.
    fn region() -> Tsr {
        Tsr::new(
            pose_from_xyz_rpy([0.45, 0.0, 0.3], [std::f64::consts::PI, 0.0, 0.0]),
            Pose::identity(),
            Bounds::symmetric(0.04, 0.3),
        )
    }

    fn goal(strategy: GoalStrategy, seed: u64) -> Candidate<()> {
        let robot = Robot::panda().unwrap();
        let options = GoalOptions {
            strategy,
            ..GoalOptions::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let found = find_goals(
            &robot,
            &region(),
            &Pose::identity(),
            robot.ready(),
            &options,
            &mut rng,
            |_, _| Ok(()),
        )
        .unwrap();
        found[0].clone()
    }

    #[test]
    fn sampled_goals_go_across_the_region_and_nominal_ones_stay_on_its_centre() {
        let tsr = region();
        let nominal = tsr.nominal();
        let sampled: Vec<Pose> = (0..6)
            .map(|seed| goal(GoalStrategy::Sampled, seed).pose)
            .collect();
        for pose in &sampled {
            assert!(tsr.contains(pose));
            assert!(position_distance(pose, &nominal) > 1e-6);
        }
        let spread = sampled
            .iter()
            .map(|p| position_distance(p, &sampled[0]))
            .fold(0.0, f64::max);
        assert!(spread > 0.01, "sampled goals barely differ: {spread}");
        for seed in 0..3 {
            let pose = goal(GoalStrategy::Nominal, seed).pose;
            assert!(position_distance(&pose, &nominal) < 1e-9);
        }
        assert_eq!(
            goal(GoalStrategy::Sampled, 4).pose,
            goal(GoalStrategy::Sampled, 4).pose
        );
    }

    #[test]
    fn sampled_poses_leave_the_nominal_out() {
        let tsr = region();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let nominal = tsr.nominal();
        let first = tsr_poses(&tsr, 5, GoalStrategy::Nominal, &mut rng);
        assert_eq!(first[0], nominal);
        let sampled = tsr_poses(&tsr, 5, GoalStrategy::Sampled, &mut rng);
        assert_eq!(sampled.len(), 5);
        assert!(sampled.iter().all(|p| *p != nominal && tsr.contains(p)));
    }

    #[test]
    fn a_region_draws_from_its_own_stream_whatever_its_place() {
        let kf = |reference: &str, x: f64| Keyframe {
            kind: KeyframeKind::Interaction,
            reference: reference.into(),
            tsr: Tsr::new(
                Pose::identity(),
                pose_from_xyz_rpy([x, 0.0, 0.1], [0.0, 0.0, 0.0]),
                Bounds::symmetric(0.01, 0.1),
            ),
            gripper: Gripper::Closed,
            constraint: Constraint::None,
            t: None,
            frame: None,
        };
        let draw = |seed: u64, k: &Keyframe| keyframe_stream(seed, k).gen::<u64>();
        let a = kf("part", 0.0);
        let mut moved = a.clone();
        moved.tsr.t0_w = pose_from_xyz_rpy([0.3, 0.1, 0.0], [0.0, 0.0, 1.0]);
        moved.t = Some(3.0);
        moved.constraint = Constraint::MoveInLine;
        moved.gripper = Gripper::Open;
        assert_eq!(draw(5, &a), draw(5, &moved), "only the region counts");
        assert_ne!(draw(5, &a), draw(6, &a));
        assert_ne!(draw(5, &a), draw(5, &kf("shelf", 0.0)));
        assert_ne!(draw(5, &a), draw(5, &kf("part", 0.001)));
        let mut wider = a.clone();
        wider.tsr.bw.0[5] = [-0.2, 0.2];
        assert_ne!(draw(5, &a), draw(5, &wider));
    }
}
