//! Straight-line TCP motion: the TCP position moves linearly and its orientation by slerp
//! between two world poses (evenly, or over the line's first part, [`TURN_PROFILES`]), sampled
//! densely; each sample is solved by inverse kinematics
//! seeded from the previous one, rejecting joint jumps, and each step is collision-checked.

use crate::collision::Hit;
use crate::space::Space;
use akl_tsr::nalgebra::{Translation3, Vector3};
use akl_tsr::Pose;
use std::fmt;

/// Settings of the line planner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineOptions {
    /// Largest TCP displacement between samples (metres).
    pub position_step: f64,
    /// Largest TCP rotation between samples (radians).
    pub rotation_step: f64,
    /// Largest change of any joint between samples (radians); more is a jump.
    pub max_joint_step: f64,
    /// Largest distance the TCP may stray from the line (metres).
    pub tolerance: f64,
}

impl Default for LineOptions {
    fn default() -> Self {
        LineOptions {
            position_step: 0.005,
            rotation_step: 0.02,
            max_joint_step: 0.15,
            tolerance: 0.001,
        }
    }
}

/// Why a line cannot be followed; `at` is the fraction of the line (0 to 1).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum LineFailure {
    /// No configuration within the joint limits reaches the pose there.
    LeavesWorkspace {
        /// Fraction of the line.
        at: f64,
    },
    /// The pose is reachable, but only by a jump of some joint (a configuration change).
    JointJump {
        /// Fraction of the line.
        at: f64,
    },
    /// The arm, hand or held object collides there.
    Collision {
        /// Fraction of the line.
        at: f64,
        /// What collides.
        hit: Hit,
    },
    /// Start and end orientations are half a turn apart: the interpolation is ambiguous.
    HalfTurn,
}

impl fmt::Display for LineFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LineFailure::LeavesWorkspace { at } => write!(
                f,
                "the line leaves the workspace {:.0} % of the way (no IK solution within the joint limits)",
                100.0 * at
            ),
            LineFailure::JointJump { at } => write!(
                f,
                "the line needs a joint jump {:.0} % of the way (the arm would have to change configuration)",
                100.0 * at
            ),
            LineFailure::Collision { at, hit } => {
                write!(f, "collision {:.0} % of the way: {hit}", 100.0 * at)
            }
            LineFailure::HalfTurn => f.write_str(
                "start and end orientations are half a turn apart; the rotation is ambiguous",
            ),
        }
    }
}

/// Distance from point `p` to the segment from `a` to `b`.
pub fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len_sq = ab.norm_squared();
    let t = if len_sq > 0.0 {
        ((p - a).dot(&ab) / len_sq).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + t * ab - p).norm()
}

/// How soon along a line the TCP's turn is done, as fractions of the line, in the order they
/// are tried: evenly over the whole line first, then within its first half or quarter. A
/// `move_in_line` constrains where the TCP goes, not when it turns; a held object that must
/// enter a tight opening square to it (the assembly's pipe, grasped a few degrees off its
/// perceived pose) enters it only if the turn is over before it gets there.
pub(crate) const TURN_PROFILES: [f64; 3] = [1.0, 0.5, 0.25];

/// Turns smaller than this (radians) are planned evenly only: every profile gives the same line.
const NEGLIGIBLE_TURN: f64 = 1e-3;

/// Joint waypoints that move the TCP from `from` (where it is at `start`) to `to` on the
/// straight line, both world poses; `base` is the robot base pose in the world. The TCP turns
/// evenly along the line, or, when that collides, faster at its start ([`TURN_PROFILES`]); the
/// first profile's failure is the one reported when none plans.
pub(crate) fn plan_line(
    space: &Space,
    start: &[f64],
    from: &Pose,
    to: &Pose,
    base: &Pose,
    options: &LineOptions,
) -> Result<Vec<Vec<f64>>, LineFailure> {
    let even = plan_line_turning(space, start, from, to, base, options, 1.0);
    let turn = from.rotation.angle_to(&to.rotation);
    match even {
        Err(LineFailure::Collision { .. }) if turn > NEGLIGIBLE_TURN => TURN_PROFILES[1..]
            .iter()
            .find_map(|&by| plan_line_turning(space, start, from, to, base, options, by).ok())
            .ok_or_else(|| even.unwrap_err()),
        other => other,
    }
}

/// [`plan_line`] with the turn done at fraction `turn_by` of the line.
fn plan_line_turning(
    space: &Space,
    start: &[f64],
    from: &Pose,
    to: &Pose,
    base: &Pose,
    options: &LineOptions,
    turn_by: f64,
) -> Result<Vec<Vec<f64>>, LineFailure> {
    let distance = (to.translation.vector - from.translation.vector).norm();
    let angle = from.rotation.angle_to(&to.rotation);
    let steps = (distance / options.position_step)
        .max(angle / (turn_by * options.rotation_step))
        .ceil()
        .max(1.0) as usize;
    let base_inv = base.inverse();
    let line = Line {
        from,
        to,
        base,
        base_inv,
        turn_by,
        options,
    };
    let mut path = vec![start.to_vec()];
    for k in 1..=steps {
        let (s0, s) = ((k - 1) as f64 / steps as f64, k as f64 / steps as f64);
        let previous = path[path.len() - 1].clone();
        line.extend(space, &mut path, &previous, s0, s, MAX_BISECTIONS)?;
    }
    Ok(path)
}

/// How many times a step of a line is halved, at most, to keep the arm's joint-space motion
/// between waypoints within the line's tolerance.
const MAX_BISECTIONS: u32 = 6;

/// A line being planned: its ends and settings.
struct Line<'a> {
    from: &'a Pose,
    to: &'a Pose,
    base: &'a Pose,
    base_inv: Pose,
    turn_by: f64,
    options: &'a LineOptions,
}

impl Line<'_> {
    /// Appends to `path` the waypoints that move the TCP from the line's fraction `s0` (where
    /// `previous` puts it) to `s`: one, or, when the joint-space motion between them strays
    /// from the line by more than the tolerance, those of the step's two halves.
    fn extend(
        &self,
        space: &Space,
        path: &mut Vec<Vec<f64>>,
        previous: &[f64],
        s0: f64,
        s: f64,
        bisections: u32,
    ) -> Result<(), LineFailure> {
        let robot = space.checker.robot();
        let pose = interpolate_turning(self.from, self.to, s, self.turn_by)
            .ok_or(LineFailure::HalfTurn)?;
        let target = self.base_inv * pose;
        let q = match robot.ik_continuous(&target, previous, self.options.max_joint_step) {
            Some(q) => q,
            None if robot.ik(&target, previous).is_err() => {
                return Err(LineFailure::LeavesWorkspace { at: s })
            }
            None => return Err(LineFailure::JointJump { at: s }),
        };
        if self.strays(space, previous, &q) {
            if bisections == 0 {
                return Err(LineFailure::JointJump { at: s });
            }
            let mid = 0.5 * (s0 + s);
            self.extend(space, path, previous, s0, mid, bisections - 1)?;
            let halfway = path[path.len() - 1].clone();
            return self.extend(space, path, &halfway, mid, s, bisections - 1);
        }
        // Past the line's start, `previous` is the end of the edge before, checked there.
        let hit = if path.len() > 1 {
            space.edge_from_valid(previous, &q)
        } else {
            space.edge(previous, &q)
        };
        if let Some(hit) = hit {
            return Err(LineFailure::Collision { at: s, hit });
        }
        path.push(q);
        Ok(())
    }

    /// Whether the TCP leaves the line by more than the tolerance anywhere on the joint-space
    /// segment from `a` to `b` (checked at its quarter points).
    fn strays(&self, space: &Space, a: &[f64], b: &[f64]) -> bool {
        let robot = space.checker.robot();
        let (p, q) = (self.from.translation.vector, self.to.translation.vector);
        let mut between = vec![0.0; a.len()];
        [0.25, 0.5, 0.75].iter().any(|&t| {
            for (m, (x, y)) in between.iter_mut().zip(a.iter().zip(b)) {
                *m = x + t * (y - x);
            }
            let at = (self.base * robot.tcp_pose(&between)).translation.vector;
            distance_to_segment(&at, &p, &q) > self.options.tolerance
        })
    }
}

/// The pose a fraction `s` of the way from `a` to `b` (position lerp, orientation slerp), with
/// the turn done at fraction `turn_by` of the way.
pub(crate) fn interpolate_turning(a: &Pose, b: &Pose, s: f64, turn_by: f64) -> Option<Pose> {
    let p = a.translation.vector.lerp(&b.translation.vector, s);
    let r = a
        .rotation
        .try_slerp(&b.rotation, (s / turn_by).min(1.0), 1e-9)?;
    Some(Pose::from_parts(Translation3::from(p), r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{Checker, RobotCollision, Scene};
    use crate::contact_rules::Allowances;
    use crate::Robot;
    use akl_scene::builtin;
    use akl_tsr::nalgebra::UnitQuaternion;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A line's start keeps its whole margin, though the line's later waypoints are taken as
    /// checked where the step before them ended: a plate just within the hand's margin under
    /// the fingers at the start stops a line that lifts the hand straight away from it.
    #[test]
    fn a_line_checks_its_start() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let start = robot.ready().to_vec();
        let world = crate::collision::tests::plate_just_within_the_margin(&robot, &model, &start);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let allow = Allowances::default();
        let space = Space {
            checker: &checker,
            width: robot.open_width(),
            held: None,
            allow: &allow,
        };
        let base = world.robot_base;
        let from = base * robot.tcp_pose(&start);
        let to = Translation3::new(0.0, 0.0, 0.05) * from;
        match plan_line(&space, &start, &from, &to, &base, &LineOptions::default()) {
            Err(LineFailure::Collision { hit, .. }) => assert!(hit.to_string().contains("plate")),
            other => panic!("expected the plate, got {other:?}"),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// A line that plans (from a random collision-free configuration to a pose up to
        /// 15 cm and 0.5 rad away) starts where the arm is, ends on the target pose, keeps the
        /// TCP within 1 mm of the segment at and between its waypoints (joint-space
        /// interpolation), stays within the joint limits and never moves a joint further than
        /// the jump threshold between waypoints.
        #[test]
        fn planned_lines_stay_on_their_line(seed in 0..100_000u64) {
            let robot = Robot::panda().unwrap();
            let model = RobotCollision::new(&robot);
            let world = builtin::task("inspection").unwrap().unwrap().world;
            let scene = Scene::new(&world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            let allow = Allowances::default();
            let space = Space { checker: &checker, width: robot.open_width(), held: None, allow: &allow };
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut start = vec![0.0; robot.dof()];
            let sampler = space.sampler();
            loop {
                sampler.fill(&mut rng, &mut start);
                if space.valid(&start) {
                    break;
                }
            }
            let base = world.robot_base;
            let from = base * robot.tcp_pose(&start);
            let offset = Vector3::from_fn(|_, _| rng.gen_range(-0.15..0.15));
            let axis = Vector3::from_fn(|_, _| rng.gen_range(-1.0..1.0));
            let turn = UnitQuaternion::from_scaled_axis(axis.normalize() * rng.gen_range(0.0..0.5));
            let to = Pose::from_parts(
                Translation3::from(from.translation.vector + offset),
                turn * from.rotation,
            );
            let options = LineOptions::default();
            // The property is about the lines that plan; others report why they cannot.
            let Ok(path) = plan_line(&space, &start, &from, &to, &base, &options) else { return Ok(()) };
            prop_assert_eq!(&path[0], &start);
            let end = base * robot.tcp_pose(&path[path.len() - 1]);
            prop_assert!((end.translation.vector - to.translation.vector).norm() < 1e-6);
            prop_assert!(end.rotation.angle_to(&to.rotation) < 1e-6);
            let (a, b) = (from.translation.vector, to.translation.vector);
            for w in path.windows(2) {
                prop_assert!(robot.check_joints(&w[1]).is_ok());
                for (x, y) in w[0].iter().zip(&w[1]) {
                    prop_assert!((y - x).abs() <= options.max_joint_step);
                }
                for k in 0..=10 {
                    let s = k as f64 / 10.0;
                    let q: Vec<f64> = w[0].iter().zip(&w[1]).map(|(x, y)| x + s * (y - x)).collect();
                    let p = (base * robot.tcp_pose(&q)).translation.vector;
                    prop_assert!(distance_to_segment(&p, &a, &b) <= 1e-3);
                }
            }
        }
    }
}
