//! The robot in the simulation: simulated joint servos that track the timed plan, and one
//! rapier body per link placed where the simulated joints put it.
//!
//! Each arm joint is a position servo like the Panda's joint controllers: a PD loop on the
//! planned position and velocity, `q̈ = ω²(q_plan − q) + 2ζω(q̇_plan − q̇)`, whose acceleration
//! is bounded by the joint's torque limit over the inertia it moves, and whose speed is bounded
//! by the joint's velocity limit. The simulated joint state, not the plan, places the links:
//! they are kinematic bodies moved to those poses each step, so they push what they touch with the joints'
//! motion and report every contact. The fingers close at the gripper's speed and stop when both
//! pads touch something (see [`crate::grasp`] for what holds the object then).
//!
//! Why servos and kinematic bodies rather than rapier's multibody joint motors: measured on
//! the same scene and step (see the README's Execution section), a multibody Panda costs about
//! 50 times the instructions per step of this model, which would put a trial far below the
//! throughput randomized verification needs, while what verification reads — where the TCP,
//! the fingers and the held object actually are, how far they lag the plan, what they touch
//! and how hard — is measured the same way. What this model leaves out is the arm yielding to
//! a contact: the Panda stops on a collision reflex when an external force exceeds its
//! thresholds, and the verifier likewise fails any contact above its force limit, so no verdict
//! depends on how the arm would have moved after it.

use crate::convert::{link_collider, to_sim};
use crate::world::{link_groups, Owner, SimWorld};
use akl_planner::collision::ExactShape;
use akl_planner::{Drive, HandModel, LocalBox, Motion, PUSH_SHARE};
use akl_planner::{Geometry, Robot, ShapeRole};
use akl_tsr::nalgebra::{Matrix3, Point3, Rotation3};
use akl_tsr::Pose;
use rapier3d::pipeline::ActiveHooks;
use rapier3d::prelude::{ActiveCollisionTypes, ColliderHandle, RigidBodyBuilder, RigidBodyHandle};

/// Friction of the finger pads and links (rubber-like pads).
pub(crate) const LINK_FRICTION: f64 = 1.0;

/// Continuous grasping force of the Franka Hand (N).
pub(crate) const FRANKA_HAND_FORCE: f64 = 70.0;

/// Largest force the Franka Hand can exert (N), briefly.
pub(crate) const FRANKA_HAND_MAX_FORCE: f64 = 140.0;

/// Largest gap (metres) between a pad and an object for the pad to touch it.
pub(crate) const PAD_CONTACT: f64 = 5e-4;

/// What one pad touches: the nearest object, how far it is, and how hard the pad pushes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PadReading {
    /// The nearest object (index), among those within rapier's contact prediction of the pad.
    pub object: Option<usize>,
    /// Its distance from the pad: a certified lower bound between the exact shapes at their
    /// current poses, in double precision (metres; infinite when nothing is near).
    pub gap: f64,
    /// Force of the pad's contacts in the last step (N).
    pub force: f64,
}

impl PadReading {
    /// A pad with nothing near it.
    pub(crate) const NOTHING: PadReading = PadReading {
        object: None,
        gap: f64::INFINITY,
        force: 0.0,
    };

    /// Whether the pad touches its nearest object ([`PAD_CONTACT`]).
    pub(crate) fn touches(&self) -> bool {
        self.object.is_some() && self.gap <= PAD_CONTACT
    }
}

/// Gains and limits of the simulated joint servos and gripper.
#[derive(Debug, Clone, PartialEq)]
pub struct Drives {
    /// Natural frequency ω/2π of each joint's position loop (Hz).
    pub frequency: f64,
    /// Damping ratio ζ of the position loop (1: critically damped).
    pub damping_ratio: f64,
    /// Largest torque of each arm joint (N·m), in joint order, overriding the robot's; joints
    /// beyond the list use its last value. Empty (the default): each joint's `effort` limit
    /// from the robot's URDF (for the Panda, 87 N·m for joints 1–4 and 12 N·m for 5–7, as
    /// Franka's datasheet gives them).
    pub torque_limits: Vec<f64>,
    /// Force the hand holds a grasped object with once closed (N): what friction at the
    /// pads can carry follows from it.
    pub grasp_force: f64,
}

impl Default for Drives {
    /// 20 Hz critically damped loops (the plan's largest joint accelerations, 7.5–20 rad/s²,
    /// then lag by under 1.3 mrad; the loop is integrated implicitly, so stable at any step),
    /// the robot's own torque limits, the Franka Hand's 70 N.
    fn default() -> Self {
        Drives {
            frequency: 20.0,
            damping_ratio: 1.0,
            torque_limits: Vec::new(),
            grasp_force: FRANKA_HAND_FORCE,
        }
    }
}

impl Drives {
    /// The torque limit (N·m) of each of `robot`'s arm joints, in joint order: the override
    /// list when given, else each joint's URDF `effort` (unlimited when the URDF gives none).
    pub fn torque_limits_of(&self, robot: &Robot) -> Vec<f64> {
        let urdf = robot.urdf();
        robot
            .joint_names()
            .iter()
            .enumerate()
            .map(
                |(j, name)| match self.torque_limits.get(j).or(self.torque_limits.last()) {
                    Some(t) => *t,
                    None => urdf
                        .joints
                        .iter()
                        .find(|u| &u.name == name)
                        .map(|u| u.limit.effort)
                        .filter(|e| *e > 0.0)
                        .unwrap_or(f64::INFINITY),
                },
            )
            .collect()
    }
}

/// What the fingers are told to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FingerCommand {
    /// Move to this opening (metres) and hold it.
    Width(f64),
    /// Close until both pads touch something, then hold.
    Grasp,
}

/// The inertia (kg·m²) each arm joint's motor turns at configuration `q`: every link beyond
/// the joint, its own inertia about the joint axis plus its mass at its distance from the axis.
fn joint_inertias(robot: &Robot, q: &[f64]) -> Vec<f64> {
    let links = robot.links();
    let poses = robot.link_poses(q, robot.open_width());
    let inertial = |name: &str| {
        robot
            .urdf()
            .links
            .iter()
            .find(|l| l.name == name)
            .map(|l| &l.inertial)
    };
    let beyond = |link: usize, joint_link: usize| {
        let mut at = Some(link);
        while let Some(i) = at {
            if i == joint_link {
                return true;
            }
            at = links[i].parent;
        }
        false
    };
    let mut out = Vec::with_capacity(robot.dof());
    for (j, link) in links.iter().enumerate() {
        let Motion::Revolute {
            axis,
            drive: Drive::Arm { .. },
        } = link.motion
        else {
            continue;
        };
        let Some(parent) = link.parent else { continue };
        let frame = poses[parent] * link.origin;
        let a = frame.rotation * axis.into_inner();
        let p = frame.translation.vector;
        let mut inertia = 0.0;
        for (i, l) in links.iter().enumerate().filter(|(i, _)| beyond(*i, j)) {
            let Some(m) = inertial(&l.name) else { continue };
            let o = &m.origin;
            let r = Rotation3::from_euler_angles(o.rpy[0], o.rpy[1], o.rpy[2]);
            let c = poses[i] * Point3::new(o.xyz[0], o.xyz[1], o.xyz[2]);
            let t = &m.inertia;
            let local = Matrix3::new(
                t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
            );
            let world = poses[i].rotation.to_rotation_matrix() * r;
            let rotated = world.matrix() * local * world.matrix().transpose();
            let lever = (c.coords - p).cross(&a).norm();
            inertia += a.dot(&(rotated * a)) + m.mass.value * lever * lever;
        }
        out.push(inertia.max(1e-4));
    }
    out
}

/// How far each pad may close in one step of `pad_step` before both pads touch: no pad passes
/// a standing object; once one pad touches, the other closes at most half its gap (the
/// touching pad pushes the object towards it).
fn closing_step(pads: &[PadReading; 2], pad_step: f64) -> f64 {
    let (a, b) = (pads[0].gap.max(0.0), pads[1].gap.max(0.0));
    match (pads[0].touches(), pads[1].touches()) {
        (true, true) => 0.0,
        (true, false) | (false, true) => (0.5 * a.max(b)).min(PUSH_SHARE * pad_step),
        (false, false) => a.min(b).min(pad_step),
    }
}

/// The simulated arm and gripper.
pub(crate) struct SimArm {
    base: Pose,
    /// Rapier body of each robot link that has collision geometry, by link index.
    bodies: Vec<Option<RigidBodyHandle>>,
    /// Every collider of the arm, with its link index.
    colliders: Vec<(ColliderHandle, usize)>,
    /// The pad collider of each finger, in the hand model's finger order.
    pads: [Option<ColliderHandle>; 2],
    /// World pose of every link at the simulated joint state.
    poses: Vec<Pose>,
    q: Vec<f64>,
    qd: Vec<f64>,
    width: f64,
    finger: FingerCommand,
    /// Largest acceleration of each joint (rad/s²): torque limit over the inertia it moves.
    accel_limits: Vec<f64>,
    velocity_limits: Vec<f64>,
    joint_limits: Vec<[f64; 2]>,
    /// How fast the opening changes (m/s): each finger moves at half this.
    opening_rate: f64,
    closed: bool,
    open_width: f64,
    gains: (f64, f64),
    hand: HandModel,
    tcp: usize,
}

impl SimArm {
    /// Moves the fingers at `scale` (in (0, 1]) of the gripper's speed, as a plan timed with
    /// that speed scale expects ([`akl_planner::PlanOptions::speed_scale`]).
    pub(crate) fn scale_finger_speed(&mut self, scale: f64) {
        self.opening_rate *= scale;
    }

    /// Adds `robot`, its base at `base`, to `sim` at configuration `q` with the fingers opened
    /// `width`; `None` when the robot has no two-finger gripper the simulation can model.
    pub(crate) fn new(
        sim: &mut SimWorld,
        robot: &Robot,
        base: Pose,
        q: &[f64],
        width: f64,
        drives: &Drives,
    ) -> Option<SimArm> {
        let hand = HandModel::new(robot)?;
        let w = 2.0 * std::f64::consts::PI * drives.frequency;
        let torques = drives.torque_limits_of(robot);
        let accel_limits = joint_inertias(robot, robot.ready())
            .iter()
            .zip(&torques)
            .map(|(inertia, torque)| torque / inertia)
            .collect();
        let mut arm = SimArm {
            base,
            bodies: Vec::with_capacity(robot.links().len()),
            colliders: Vec::new(),
            pads: [None; 2],
            poses: vec![Pose::identity(); robot.links().len()],
            q: q.to_vec(),
            qd: vec![0.0; q.len()],
            width,
            finger: FingerCommand::Width(width),
            accel_limits,
            velocity_limits: robot.velocity_limits().to_vec(),
            joint_limits: robot.joint_limits().to_vec(),
            opening_rate: 2.0 * robot.finger_speed(),
            closed: false,
            open_width: robot.open_width(),
            gains: (w * w, 2.0 * drives.damping_ratio * w),
            hand,
            tcp: robot.tcp_link(),
        };
        arm.compute(robot);
        for (i, link) in robot.links().iter().enumerate() {
            let shapes: Vec<(Geometry, Pose)> = if let Some(finger) = arm.hand.finger(i) {
                // The pad, and the finger's other primitives as the URDF gives them (the
                // capsules around its visual mesh are the planner's).
                let others = link
                    .shapes
                    .iter()
                    .filter(|s| s.role == ShapeRole::Exact)
                    .enumerate()
                    .filter(|(k, _)| *k != finger.pad_element)
                    .map(|(_, s)| (s.geometry.clone(), s.origin));
                std::iter::once(finger.pad.geometry())
                    .chain(others)
                    .collect()
            } else if i == arm.hand.palm_link {
                arm.hand.palm.iter().map(LocalBox::geometry).collect()
            } else {
                link.shapes
                    .iter()
                    .map(|s| (s.geometry.clone(), s.origin))
                    .collect()
            };
            if shapes.is_empty() {
                arm.bodies.push(None);
                continue;
            }
            let physics = &mut sim.physics;
            let body = physics.bodies.insert(
                RigidBodyBuilder::kinematic_position_based()
                    .pose(to_sim(&arm.poses[i]))
                    .build(),
            );
            // The pads' contacts with a welded object are left out while it is welded.
            let hooks = if arm.hand.finger(i).is_some() {
                ActiveHooks::FILTER_CONTACT_PAIRS
            } else {
                ActiveHooks::empty()
            };
            for (geometry, origin) in shapes {
                let collider = link_collider(&geometry, &origin)
                    .active_hooks(hooks)
                    .friction(LINK_FRICTION as f32)
                    .restitution(0.0)
                    .collision_groups(link_groups())
                    .active_collision_types(ActiveCollisionTypes::all())
                    .user_data(Owner::Link(i).to_user_data());
                let handle =
                    physics
                        .colliders
                        .insert_with_parent(collider, body, &mut physics.bodies);
                sim.exact
                    .insert(handle, ExactShape::of_element(&geometry), origin);
                // A finger's first collider is its pad.
                if let Some(k) = arm.hand.fingers.iter().position(|f| f.link == i) {
                    arm.pads[k].get_or_insert(handle);
                }
                arm.colliders.push((handle, i));
            }
            arm.bodies.push(Some(body));
        }
        Some(arm)
    }

    fn compute(&mut self, robot: &Robot) {
        robot
            .kinematics()
            .link_poses_into(&self.q, self.width, &mut self.poses);
        for p in &mut self.poses {
            *p = self.base * *p;
        }
    }

    /// Advances the joint servos by `dt` towards the planned position `q` and velocity `qd`,
    /// and the fingers towards their command, then sets the link bodies' targets for the
    /// coming physics step. `pads` say what each pad touches: a closing hand never moves a pad
    /// past an object in one step, and stops when both pads touch.
    pub(crate) fn advance(
        &mut self,
        sim: &mut SimWorld,
        robot: &Robot,
        (q, qd): (&[f64], &[f64]),
        pads: &[PadReading; 2],
        dt: f64,
    ) {
        let (k, d) = self.gains;
        for j in 0..self.q.len() {
            let a_max = self.accel_limits[j];
            // Implicit in the step's end state (so stable at any gain): the acceleration that
            // the PD law asks for given where the joint will be after the step.
            let a = (k * (q[j] - self.q[j] - self.qd[j] * dt) + d * (qd[j] - self.qd[j]))
                / (1.0 + k * dt * dt + d * dt);
            let a = a.clamp(-a_max, a_max);
            let v_max = self
                .velocity_limits
                .get(j)
                .copied()
                .unwrap_or(f64::INFINITY);
            self.qd[j] = (self.qd[j] + a * dt).clamp(-v_max, v_max);
            let [lo, hi] = self.joint_limits[j];
            self.q[j] = (self.q[j] + self.qd[j] * dt).clamp(lo, hi);
            if self.q[j] == lo || self.q[j] == hi {
                self.qd[j] = 0.0;
            }
        }
        // Each pad moves half the change of the opening.
        let pad_step = 0.5 * self.opening_rate * dt;
        let closing = closing_step(pads, pad_step);
        self.closed = false;
        self.width = match self.finger {
            FingerCommand::Width(w) => {
                let w = w.clamp(0.0, self.open_width);
                if w < self.width {
                    self.width - (self.width - w).min(2.0 * closing)
                } else {
                    self.width + (w - self.width).min(2.0 * pad_step)
                }
            }
            FingerCommand::Grasp if pads[0].touches() && pads[1].touches() => {
                self.closed = true;
                self.width
            }
            FingerCommand::Grasp => (self.width - 2.0 * closing).max(0.0),
        };
        self.compute(robot);
        for (body, pose) in self.bodies.iter().zip(&self.poses) {
            if let Some(b) = body.and_then(|b| sim.physics.bodies.get_mut(b)) {
                b.set_next_kinematic_position(to_sim(pose));
            }
        }
    }

    /// Whether a closing hand has closed: both pads touch what is between them.
    pub(crate) fn closed(&self) -> bool {
        self.closed
    }

    /// Sets what the fingers do from now on.
    pub(crate) fn command_fingers(&mut self, command: FingerCommand) {
        self.finger = command;
    }

    /// Whether the fingers are closing (a grasp, or an opening narrower than now): what they
    /// touch then decides how far they move.
    pub(crate) fn closing(&self) -> bool {
        match self.finger {
            FingerCommand::Grasp => true,
            FingerCommand::Width(w) => w < self.width,
        }
    }

    /// World pose of every link at the simulated joint state (what the bodies are moved to).
    pub(crate) fn link_poses(&self) -> &[Pose] {
        &self.poses
    }

    /// The world pose of link `link`'s body, read from the simulation.
    pub(crate) fn body_pose(&self, sim: &SimWorld, link: usize) -> Option<Pose> {
        let body = self.bodies.get(link).copied().flatten()?;
        Some(crate::convert::from_sim(
            sim.physics.bodies[body].position(),
        ))
    }

    /// The simulated tool centre point, read from the hand's body in the simulation.
    pub(crate) fn tcp(&self, sim: &SimWorld) -> Pose {
        let palm = self.hand.palm_link;
        let on_hand = self.poses[palm].inverse() * self.poses[self.tcp];
        self.body_pose(sim, palm).unwrap_or(self.poses[palm]) * on_hand
    }

    /// The simulated joint positions.
    pub(crate) fn joint_positions(&self) -> &[f64] {
        &self.q
    }

    /// The simulated opening between the pads (metres).
    pub(crate) fn width(&self) -> f64 {
        self.width
    }

    /// The hand model (pads and palm).
    pub(crate) fn hand(&self) -> &HandModel {
        &self.hand
    }

    /// The pad collider of finger `k` (in the hand model's order).
    pub(crate) fn pad_collider(&self, k: usize) -> Option<ColliderHandle> {
        self.pads.get(k).copied().flatten()
    }

    /// The rapier body of link `link`, if it has collision geometry.
    pub(crate) fn body(&self, link: usize) -> Option<RigidBodyHandle> {
        self.bodies.get(link).copied().flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Physics;
    use akl_tsr::pose::position_distance;

    const FREE_PADS: [PadReading; 2] = [PadReading::NOTHING; 2];

    fn empty() -> akl_scene::World {
        akl_scene::World {
            robot_base: Pose::identity(),
            objects: Vec::new(),
        }
    }

    fn arm(drives: &Drives) -> (Robot, SimWorld, SimArm) {
        let robot = Robot::panda().unwrap();
        let mut sim = SimWorld::new(&empty(), &Physics::default());
        let q = robot.ready().to_vec();
        let arm = SimArm::new(&mut sim, &robot, Pose::identity(), &q, 0.08, drives).unwrap();
        (robot, sim, arm)
    }

    /// Follows a 1 s smooth move of every joint; returns the largest TCP error.
    fn follow(robot: &Robot, sim: &mut SimWorld, arm: &mut SimArm) -> f64 {
        let q0 = robot.ready().to_vec();
        let q1: Vec<f64> = q0.iter().map(|v| v + 0.5).collect();
        let dt = sim.dt();
        let n = (1.0 / dt) as usize;
        let mut worst: f64 = 0.0;
        for i in 1..=n + 60 {
            let s = (i as f64 / n as f64).min(1.0);
            let blend = s * s * (3.0 - 2.0 * s);
            let rate = if i <= n { 6.0 * s * (1.0 - s) } else { 0.0 };
            let q: Vec<f64> = q0
                .iter()
                .zip(&q1)
                .map(|(a, b)| a + blend * (b - a))
                .collect();
            let qd: Vec<f64> = q0.iter().zip(&q1).map(|(a, b)| rate * (b - a)).collect();
            arm.advance(sim, robot, (&q, &qd), &FREE_PADS, dt);
            sim.step();
            worst = worst.max(position_distance(&arm.tcp(sim), &robot.tcp_pose(&q)));
        }
        worst
    }

    #[test]
    fn the_servos_track_a_smooth_move_within_a_millimetre() {
        let (robot, mut sim, mut arm) = arm(&Drives::default());
        let worst = follow(&robot, &mut sim, &mut arm);
        assert!(worst < 1e-3, "tracking error {worst}");
    }

    #[test]
    fn weak_motors_lag_the_plan() {
        let weak = Drives {
            frequency: 2.0,
            torque_limits: vec![5.0],
            ..Drives::default()
        };
        let (robot, mut sim, mut arm) = arm(&weak);
        let worst = follow(&robot, &mut sim, &mut arm);
        assert!(worst > 0.01, "tracking error {worst}");
    }

    #[test]
    fn the_wrist_moves_a_lighter_load_than_the_shoulder() {
        let robot = Robot::panda().unwrap();
        let inertia = joint_inertias(&robot, robot.ready());
        assert_eq!(inertia.len(), 7);
        assert!(inertia[0] > 10.0 * inertia[6], "{inertia:?}");
        assert!(inertia.iter().all(|i| i.is_finite() && *i > 0.0));
    }

    #[test]
    fn the_bodies_follow_the_simulated_joints() {
        let (robot, mut sim, mut arm) = arm(&Drives::default());
        let q = robot.ready().to_vec();
        let qd = vec![0.0; 7];
        let dt = sim.dt();
        arm.advance(&mut sim, &robot, (&q, &qd), &FREE_PADS, dt);
        sim.step();
        for (i, pose) in arm.link_poses().iter().enumerate() {
            if let Some(read) = arm.body_pose(&sim, i) {
                assert!(position_distance(&read, pose) < 1e-5, "link {i}");
            }
        }
    }
}
