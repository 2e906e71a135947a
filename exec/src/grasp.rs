//! Grasps in the simulation: what the pads touch, whether a closed hand holds an object
//! soundly, and the weld that carries it while friction could.
//!
//! Why a weld and not friction alone: measured with the Panda closing its pads on a 0.2 kg
//! block at 70 N and carrying it (lift, then 0.35 m sideways in 0.6 s), rapier's contacts let
//! the pads sink 2.5 mm into the block and the block slip 21 mm at 1/240 s (8 solver
//! iterations), 20 mm at 1/480 s and 7 mm at 1/960 s; with contacts 16 times stiffer the pads
//! stay within 0.3 mm but the block falls out. A 5 mm slip limit would fail sound grasps, so
//! the simulation welds the object to the hand instead — only when the grasp is sound:
//! - both pads touch the same object ([`crate::arm::PAD_CONTACT`]);
//! - the object's centre is within [`GraspLimits::max_centre_offset`] of the pads' mid-plane;
//! - each pad overlaps the object over at least [`GraspLimits::min_overlap`] of its face;
//!
//! While welded, the pads' contacts with the object are not computed, so the weld carries
//! the whole load; and the weld breaks when that load exceeds what friction could hold: the force along
//! the pads' faces above `2 μ F` (two pads squeezing with the hand's force `F`, friction `μ`
//! combined as rapier does, the mean of pad and object), or the torque about the closing axis
//! above `2 μ F r` (`r` a quarter of the smaller side of the overlap). A broken weld lets the
//! object go, and the slip check sees it.

use crate::arm::{PadReading, SimArm, LINK_FRICTION};
use crate::convert::to_sim;
use crate::world::{Owner, SimWorld};
use akl_planner::{squared_in_hand, squaring_turn, Finger};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use rapier3d::prelude::{FixedJointBuilder, ImpulseJointHandle, RigidBodyType, SpringCoefficients};
use serde::Serialize;

/// How the weld gives: rapier's soft-constraint model at 60 Hz, critically damped, for the
/// compliance of rubber pads and fingers. Chosen by measurement over 40 randomized trials of
/// each ground truth: at 20 Hz held objects sag 3 mm in the hand (placements then press their
/// support), at 200 Hz and stiffer a weld made while the object rests on its support fights
/// that contact; at 60 Hz objects move at most 0.3 mm in the hand.
pub(crate) const WELD_SOFTNESS: SpringCoefficients<f32> = SpringCoefficients {
    natural_frequency: 60.0,
    damping_ratio: 1.0,
};

/// Limits of a sound grasp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspLimits {
    /// Largest distance (metres) of the object's centre from the mid-plane between the pads.
    pub max_centre_offset: f64,
    /// Smallest share of each pad's face the object must cover (0–1).
    pub min_overlap: f64,
}

impl Default for GraspLimits {
    /// 1 cm off the mid-plane (the pads centre what they close on; a larger offset means the
    /// object is wedged); a quarter of each pad's face (the ground truths' grasps cover 60–100 %
    /// of it, fingertips on an edge a few per cent).
    fn default() -> Self {
        GraspLimits {
            max_centre_offset: 0.01,
            min_overlap: 0.25,
        }
    }
}

/// What each pad touches now.
pub(crate) fn read_pads(sim: &SimWorld, arm: &SimArm) -> [PadReading; 2] {
    let mut pads = [PadReading::NOTHING; 2];
    for (k, reading) in pads.iter_mut().enumerate() {
        let Some(collider) = arm.pad_collider(k) else {
            continue;
        };
        for pair in sim.physics.narrow_phase.contact_pairs_with(collider) {
            let other = if pair.collider1 == collider {
                pair.collider2
            } else {
                pair.collider1
            };
            let Some(Owner::Object(o)) = sim.owner(other) else {
                continue;
            };
            reading.force += f64::from(pair.total_impulse_magnitude()) / sim.dt();
            let (colliders, bodies) = (&sim.physics.colliders, &sim.physics.bodies);
            let Some(d) = sim.exact.distance(colliders, bodies, [collider, other]) else {
                continue;
            };
            if d < reading.gap {
                reading.gap = d;
                reading.object = Some(o);
            }
        }
    }
    pads
}

/// What pushed object `object` hardest in the last step (another object, or a robot link),
/// and how hard (N); `None` when nothing did. Names the cause when a weld breaks: a held
/// object struck in passing breaks loose in one step, too briefly for a contact verdict.
pub(crate) fn strongest_push(sim: &SimWorld, object: usize) -> Option<(Owner, f64)> {
    let me = Owner::Object(object);
    sim.physics
        .narrow_phase
        .contact_pairs()
        .filter_map(|pair| {
            let (a, b) = (sim.owner(pair.collider1)?, sim.owner(pair.collider2)?);
            let other = match (a == me, b == me) {
                (true, false) => b,
                (false, true) => a,
                _ => return None,
            };
            let force = f64::from(pair.total_impulse_magnitude()) / sim.dt();
            (force > 0.0).then_some((other, force))
        })
        .max_by(|x, y| x.1.total_cmp(&y.1))
}

/// How a closed hand holds an object, measured on the simulated bodies.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraspMeasure {
    /// Distance of the object's centre from the pads' mid-plane (metres).
    pub centre_offset: f64,
    /// Distance of the object's centre from the point midway between the pads' face centres
    /// (metres).
    pub offset_from_pads: f64,
    /// The smaller of the two pads' covered shares of their faces (0–1).
    pub overlap: f64,
    /// Lever (metres) over which the pads resist a turn about the closing axis.
    pub lever: f64,
}

/// The share of a pad's face an object covers, and the smaller side of the covered patch,
/// with the object's bounding box taken in the pad's frame.
fn pad_overlap(finger: &Finger, pad_pose: &Pose, object: &Pose, half: &Vector3<f64>) -> (f64, f64) {
    let in_pad = pad_pose.inverse() * object;
    let r = in_pad.rotation.to_rotation_matrix();
    let extent = r.matrix().abs() * half;
    let c = in_pad.translation.vector;
    let pad = &finger.pad;
    let normal = finger.inward.iamax();
    let mut share = 1.0;
    let mut smaller = f64::INFINITY;
    for k in (0..3).filter(|&k| k != normal) {
        let lo = (pad.centre[k] - pad.half[k]).max(c[k] - extent[k]);
        let hi = (pad.centre[k] + pad.half[k]).min(c[k] + extent[k]);
        let covered = (hi - lo).max(0.0);
        share *= covered / (2.0 * pad.half[k]);
        smaller = smaller.min(covered);
    }
    (share, smaller)
}

/// Measures the grasp of object `object` by the simulated hand.
pub(crate) fn measure(sim: &SimWorld, arm: &SimArm, object: usize) -> GraspMeasure {
    let hand = arm.hand();
    let pose = sim.object_pose(object);
    let half = sim.template().objects[object].shape.half_extents();
    let mut faces = Vec::with_capacity(2);
    let mut overlap = f64::INFINITY;
    let mut lever = f64::INFINITY;
    for finger in &hand.fingers {
        let pad_pose = arm.link_poses()[finger.link];
        faces.push(pad_pose * akl_tsr::nalgebra::Point3::from(finger.face_centre()));
        let (share, side) = pad_overlap(finger, &pad_pose, &pose, &half);
        overlap = overlap.min(share);
        lever = lever.min(0.25 * side);
    }
    let centre = pose.translation.vector;
    let mid = 0.5 * (faces[0].coords + faces[1].coords);
    let closing = (faces[1] - faces[0]).normalize();
    GraspMeasure {
        centre_offset: (centre - mid).dot(&closing).abs(),
        offset_from_pads: (centre - mid).norm(),
        overlap,
        lever,
    }
}

impl GraspMeasure {
    /// Why the grasp is not sound under `limits`, or `None` when it is.
    pub fn unsound(&self, limits: &GraspLimits) -> Option<String> {
        if self.centre_offset > limits.max_centre_offset {
            return Some(format!(
                "its centre is {:.1} mm off the pads' mid-plane (limit {:.1} mm)",
                self.centre_offset * 1e3,
                limits.max_centre_offset * 1e3
            ));
        }
        if self.overlap < limits.min_overlap {
            return Some(format!(
                "the pads cover only {:.0} % of their faces with it (at least {:.0} % needed)",
                self.overlap * 100.0,
                limits.min_overlap * 100.0
            ));
        }
        None
    }
}

/// Seats object `object` between the closed pads of `arm` as their squeeze does
/// ([`akl_planner::squared_in_hand`], the rule the planner's held model follows): turned about the
/// hand's approach axis until it lies flat on the pads, and a cylinder held by its side stood
/// up between them. Returns the turn about the approach axis (radians).
pub(crate) fn square(sim: &mut SimWorld, arm: &SimArm, object: usize) -> f64 {
    let tcp = arm.tcp(sim);
    let shape = sim.template().objects[object].shape.clone();
    let in_tcp = tcp.inverse() * sim.object_pose(object);
    let seated = squared_in_hand(&shape, &in_tcp);
    if seated != in_tcp {
        sim.set_object_pose(object, &(tcp * seated));
    }
    squaring_turn(&shape, &in_tcp)
}

/// An object welded to the hand while friction could hold it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Weld {
    /// Index of the object in [`SimWorld::objects`].
    pub object: usize,
    /// Its pose in the TCP frame when welded.
    pub in_tcp: Pose,
    joint: ImpulseJointHandle,
    /// The pads' links, whose contacts with the object are left out while it is welded.
    pads: [usize; 2],
    /// Largest force along the pads' faces friction holds (N).
    pub force_capacity: f64,
    /// Largest torque about the closing axis friction holds (N·m).
    pub torque_capacity: f64,
    /// The closing axis in the TCP frame.
    closing: Vector3<f64>,
}

/// The load on a weld in one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WeldLoad {
    /// Force along the pads' faces (N).
    pub force: f64,
    /// Torque about the closing axis (N·m).
    pub torque: f64,
}

impl Weld {
    /// Welds object `object` to the hand of `arm` as it is now, squeezed with `grasp_force`.
    pub(crate) fn attach(
        sim: &mut SimWorld,
        arm: &SimArm,
        object: usize,
        grasp: &GraspMeasure,
        grasp_force: f64,
    ) -> Option<Weld> {
        let palm = arm.hand().palm_link;
        let palm_body = arm.body(palm)?;
        let tcp = arm.tcp(sim);
        let palm_pose = arm.body_pose(sim, palm)?;
        let object_pose = sim.object_pose(object);
        let mu = 0.5 * (LINK_FRICTION + sim.template().objects[object].friction);
        let fingers = &arm.hand().fingers;
        let faces: Vec<Vector3<f64>> = fingers
            .iter()
            .map(|f| {
                let pose = arm.link_poses()[f.link];
                (pose * akl_tsr::nalgebra::Point3::from(f.face_centre())).coords
            })
            .collect();
        let closing = tcp.rotation.inverse() * (faces[1] - faces[0]).normalize();
        let joint = FixedJointBuilder::new()
            .local_frame1(to_sim(&(palm_pose.inverse() * tcp)))
            .local_frame2(to_sim(&(object_pose.inverse() * tcp)))
            .contacts_enabled(false)
            .softness(WELD_SOFTNESS)
            .build();
        let object_body = sim.objects[object].body;
        let joint = sim
            .physics
            .impulse_joints
            .insert(palm_body, object_body, joint, true);
        for f in fingers {
            sim.set_unsolved(f.link, object, true);
        }
        let pads = [fingers[0].link, fingers[1].link];
        Some(Weld {
            object,
            in_tcp: tcp.inverse() * object_pose,
            joint,
            pads,
            force_capacity: 2.0 * mu * grasp_force,
            torque_capacity: 2.0 * mu * grasp_force * grasp.lever,
            closing,
        })
    }

    /// The load the weld carried in the last step.
    pub(crate) fn load(&self, sim: &SimWorld) -> WeldLoad {
        let Some(joint) = sim.physics.impulse_joints.get(self.joint) else {
            return WeldLoad {
                force: 0.0,
                torque: 0.0,
            };
        };
        // A joint's impulses are its last substep's.
        let dt = sim.dt() / sim.substeps() as f64;
        let i = joint.impulses;
        let linear = Vector3::new(f64::from(i[0]), f64::from(i[1]), f64::from(i[2])) / dt;
        let angular = Vector3::new(f64::from(i[3]), f64::from(i[4]), f64::from(i[5])) / dt;
        let along_faces = linear - linear.dot(&self.closing) * self.closing;
        WeldLoad {
            force: along_faces.norm(),
            torque: angular.dot(&self.closing).abs(),
        }
    }

    /// Whether `load` is more than friction could hold.
    pub(crate) fn overloaded(&self, load: &WeldLoad) -> bool {
        load.force > self.force_capacity || load.torque > self.torque_capacity
    }

    /// The part of `load` friction could not hold, in words: a force along the pads' faces,
    /// or a torque about the closing axis.
    pub(crate) fn overload_text(&self, load: &WeldLoad) -> String {
        if load.force > self.force_capacity {
            format!(
                "a force of {:.0} N along the pads, more than the {:.0} N friction holds",
                load.force, self.force_capacity
            )
        } else {
            format!(
                "a torque of {:.2} N·m about the closing axis, more than the {:.2} N·m friction holds",
                load.torque, self.torque_capacity
            )
        }
    }

    /// Removes the weld: the object is free and physics takes over.
    pub(crate) fn release(self, sim: &mut SimWorld) {
        sim.physics.impulse_joints.remove(self.joint, true);
        for pad in self.pads {
            sim.set_unsolved(pad, self.object, false);
        }
        if let Some(body) = sim.physics.bodies.get_mut(sim.objects[self.object].body) {
            if body.body_type() != RigidBodyType::Dynamic {
                body.set_body_type(RigidBodyType::Dynamic, true);
            }
        }
    }

    /// How far (metres) the object has moved in the hand since it was welded.
    #[cfg(test)]
    pub(crate) fn slip(&self, sim: &SimWorld, tcp: &Pose) -> f64 {
        let now = tcp.inverse() * sim.object_pose(self.object);
        (now.translation.vector - self.in_tcp.translation.vector).norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::{Drives, FingerCommand};
    use crate::world::Physics;
    use akl_planner::Robot;
    use akl_scene::{Object, Shape, World};
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};
    use std::f64::consts::PI;

    /// A 5 × 5 × 8 cm block of `mass` standing on a table (object 0 the table, 1 the block).
    fn block_on_table(mass: f64) -> World {
        World {
            robot_base: Pose::identity(),
            objects: vec![
                Object {
                    name: "table".into(),
                    shape: Shape::Box {
                        size: [0.6, 0.6, 0.04],
                    },
                    pose: pose_from_xyz([0.5, 0.0, -0.02]),
                    movable: false,
                    mass: 0.0,
                    friction: 0.6,
                },
                Object {
                    name: "block".into(),
                    shape: Shape::Box {
                        size: [0.05, 0.05, 0.08],
                    },
                    pose: pose_from_xyz([0.5, 0.0, 0.04]),
                    movable: true,
                    mass,
                    friction: 0.9,
                },
            ],
        }
    }

    /// A block of `mass` on a table, the hand closed on it, welded, then lifted 5 cm in 0.5 s:
    /// the largest load along the pads' faces, the capacity, and the slip at the end.
    fn lift(mass: f64) -> (f64, f64, f64) {
        let robot = Robot::panda().unwrap();
        let world = block_on_table(mass);
        let mut sim = SimWorld::new(&world, &Physics::default());
        let grasp = pose_from_xyz_rpy([0.5, 0.0, 0.055], [PI, 0.0, 0.0]);
        let q0 = robot.ik(&grasp, robot.ready()).unwrap();
        let mut arm = SimArm::new(
            &mut sim,
            &robot,
            Pose::identity(),
            &q0,
            0.08,
            &Drives::default(),
        )
        .unwrap();
        arm.command_fingers(FingerCommand::Grasp);
        let still = vec![0.0; q0.len()];
        let dt = sim.dt();
        for _ in 0..240 {
            let pads = read_pads(&sim, &arm);
            arm.advance(&mut sim, &robot, (&q0, &still), &pads, dt);
            sim.step();
            if arm.closed() {
                break;
            }
        }
        assert!(arm.closed(), "the pads closed on the block");
        let grasped = measure(&sim, &arm, 1);
        assert!(grasped.unsound(&GraspLimits::default()).is_none());
        let weld =
            Weld::attach(&mut sim, &arm, 1, &grasped, crate::arm::FRANKA_HAND_FORCE).unwrap();
        arm.command_fingers(FingerCommand::Width(arm.width()));
        let up = robot
            .ik(&(pose_from_xyz([0.0, 0.0, 0.05]) * grasp), &q0)
            .unwrap();
        let mut peak: f64 = 0.0;
        let mut held = Some(weld);
        for k in 1..=240 {
            let s = (f64::from(k) / 120.0).min(1.0);
            let q: Vec<f64> = q0.iter().zip(&up).map(|(a, b)| a + s * (b - a)).collect();
            let rate = if k <= 120 { 2.0 } else { 0.0 };
            let qd: Vec<f64> = q0.iter().zip(&up).map(|(a, b)| rate * (b - a)).collect();
            arm.advance(&mut sim, &robot, (&q, &qd), &[PadReading::NOTHING; 2], dt);
            sim.step();
            if let Some(w) = held {
                let load = w.load(&sim);
                peak = peak.max(load.force);
                if w.overloaded(&load) {
                    w.release(&mut sim);
                    held = None;
                }
            }
        }
        (peak, weld.force_capacity, weld.slip(&sim, &arm.tcp(&sim)))
    }

    #[test]
    fn a_light_block_stays_welded_and_a_heavy_one_breaks_loose() {
        let (peak, capacity, slip) = lift(0.2);
        assert!(
            peak < capacity && slip < 1e-3,
            "{peak} N of {capacity} N, slip {slip}"
        );
        // Its weight, and the lift's acceleration: the load is measured in newtons.
        assert!(peak > 0.2 * 9.81 && peak < 0.2 * 15.0, "{peak} N");
        assert!((capacity - 2.0 * 0.95 * 70.0).abs() < 1e-9);
        // 20 kg weigh 196 N, more than the 133 N two pads at 70 N hold by friction.
        let (peak, capacity, slip) = lift(20.0);
        assert!(peak > capacity, "{peak} N of {capacity} N");
        assert!(slip > 0.005, "the block fell out of the hand: slip {slip}");
    }

    /// A block resting on a table is pushed hardest by the table, with its weight.
    #[test]
    fn the_strongest_push_on_a_resting_block_is_its_support() {
        let world = block_on_table(0.2);
        let mut sim = SimWorld::new(&world, &Physics::default());
        for _ in 0..120 {
            sim.step();
        }
        let (by, force) = strongest_push(&sim, 1).unwrap();
        assert_eq!(by, Owner::Object(0));
        assert!((force - 0.2 * 9.81).abs() < 0.1, "{force} N");
        assert_eq!(strongest_push(&sim, 0).map(|p| p.0), Some(Owner::Object(1)));
    }
}
