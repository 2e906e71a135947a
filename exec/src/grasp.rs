//! Grasping and releasing in the simulation.
//!
//! When the gripper has closed, an object counts as grasped when its shape reaches into the
//! space between the finger pads; it is then attached to the hand: switched to a kinematic
//! body that follows the TCP rigidly with the offset it had at that moment. A release
//! switches it back to a dynamic body at rest, and physics settles it. Rigid attachment
//! rather than friction: the verification is about the spec, and a friction grasp in a
//! position-based simulation would add slip that depends on solver settings, not on it.

use crate::convert::{link_collider, to_sim};
use crate::world::SimWorld;
use akl_planner::Robot;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use rapier3d::parry::query::intersection_test;
use rapier3d::parry::shape::Cuboid;
use rapier3d::prelude::{RigidBodyType, Vector};

/// How far (metres) the space between the fingers is grown on every side, so that an object
/// the pads touch (rather than reach into) counts as between them.
pub const GAP_GROWTH: f64 = 1e-3;

/// The space between the finger pads: a box in the TCP frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerGap {
    centre: Vector3<f64>,
    half: Vector3<f64>,
}

impl FingerGap {
    /// The space between the two finger links of `robot` opened `width`: the overlap of the
    /// fingers' bounding boxes (in the TCP frame) along the other two axes, between their
    /// facing sides along the axis they close on. `None` when the fingers touch or the robot
    /// does not have two fingers.
    pub fn new(robot: &Robot, width: f64) -> Option<FingerGap> {
        let fingers: Vec<usize> = robot
            .links()
            .iter()
            .enumerate()
            .filter(|(_, l)| robot.finger_joints().contains(&l.joint))
            .map(|(i, _)| i)
            .collect();
        let [a, b] = fingers[..] else {
            return None;
        };
        let poses = robot.link_poses(robot.ready(), width);
        let tcp_inv = poses[robot.tcp_link()].inverse();
        let bounds = |link: usize| -> Option<(Vector3<f64>, Vector3<f64>)> {
            let in_tcp = tcp_inv * poses[link];
            let mut lo = Vector3::repeat(f64::INFINITY);
            let mut hi = Vector3::repeat(f64::NEG_INFINITY);
            for shape in &robot.links()[link].shapes {
                let aabb = link_collider(&shape.geometry, &(in_tcp * shape.origin))
                    .build()
                    .compute_aabb();
                for k in 0..3 {
                    lo[k] = lo[k].min(f64::from(aabb.mins[k]));
                    hi[k] = hi[k].max(f64::from(aabb.maxs[k]));
                }
            }
            (lo.x <= hi.x).then_some((lo, hi))
        };
        let (lo_a, hi_a) = bounds(a)?;
        let (lo_b, hi_b) = bounds(b)?;
        // The closing axis is the one along which the fingers are apart.
        let gaps = Vector3::from_fn(|k, _| (lo_a[k] - hi_b[k]).max(lo_b[k] - hi_a[k]));
        let axis = gaps.imax();
        if gaps[axis] <= 0.0 {
            return None;
        }
        let mut lo = lo_a.sup(&lo_b);
        let mut hi = hi_a.inf(&hi_b);
        lo[axis] = hi_a[axis].min(hi_b[axis]);
        hi[axis] = lo_a[axis].max(lo_b[axis]);
        if (0..3).any(|k| hi[k] < lo[k]) {
            return None;
        }
        Some(FingerGap {
            centre: 0.5 * (lo + hi),
            half: 0.5 * (hi - lo) + Vector3::repeat(GAP_GROWTH),
        })
    }

    /// Whether object `object` of `sim` reaches into the gap of a hand whose TCP is at `tcp`.
    pub fn holds(&self, sim: &SimWorld, tcp: &Pose, object: usize) -> bool {
        let Some(collider) = sim.physics.colliders.get(sim.objects[object].collider) else {
            return false;
        };
        let gap = tcp * Pose::translation(self.centre.x, self.centre.y, self.centre.z);
        let cuboid = Cuboid::new(Vector::new(
            self.half.x as f32,
            self.half.y as f32,
            self.half.z as f32,
        ));
        intersection_test(
            &to_sim(&gap),
            &cuboid,
            collider.position(),
            collider.shape(),
        )
        .is_ok_and(|r| r.intersecting)
    }

    /// Half extents of the gap (metres, TCP frame).
    pub fn half_extents(&self) -> Vector3<f64> {
        self.half
    }
}

/// An object attached to the hand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Held {
    /// Index of the object in [`SimWorld::objects`].
    pub object: usize,
    /// Its pose in the TCP frame, fixed at the grasp.
    pub in_tcp: Pose,
}

impl Held {
    /// Attaches object `object` to a hand whose TCP is at `tcp`.
    pub fn attach(sim: &mut SimWorld, object: usize, tcp: &Pose) -> Held {
        let in_tcp = tcp.inverse() * sim.object_pose(object);
        if let Some(body) = sim.physics.bodies.get_mut(sim.objects[object].body) {
            body.set_body_type(RigidBodyType::KinematicPositionBased, true);
        }
        Held { object, in_tcp }
    }

    /// Moves the held object with a TCP that will be at `tcp` after the next step.
    pub fn follow(&self, sim: &mut SimWorld, tcp: &Pose) {
        if let Some(body) = sim.physics.bodies.get_mut(sim.objects[self.object].body) {
            body.set_next_kinematic_position(to_sim(&(tcp * self.in_tcp)));
        }
    }

    /// Lets go: the object becomes dynamic again, at rest, and physics settles it.
    pub fn release(self, sim: &mut SimWorld) {
        if let Some(body) = sim.physics.bodies.get_mut(sim.objects[self.object].body) {
            body.set_body_type(RigidBodyType::Dynamic, true);
            body.set_linvel(Vector::ZERO, true);
            body.set_angvel(Vector::ZERO, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Physics;
    use akl_scene::{Object, Shape, World};
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy, position_distance};
    use std::f64::consts::PI;

    #[test]
    fn the_panda_gap_lies_between_the_pads_across_the_tcp_y_axis() {
        let robot = Robot::panda().unwrap();
        let gap = FingerGap::new(&robot, 0.05).unwrap();
        let h = gap.half_extents();
        assert!((h.y - (0.025 + GAP_GROWTH)).abs() < 1e-5, "{h:?}");
        assert!(h.x < 0.02 && h.z > 0.01, "{h:?}");
        assert!(gap.centre.y.abs() < 1e-9 && gap.centre.x.abs() < 1e-9);
        assert!(FingerGap::new(&robot, 0.0).is_none());
    }

    fn one_block() -> World {
        World {
            robot_base: Pose::identity(),
            objects: vec![Object {
                name: "block".into(),
                shape: Shape::Box {
                    size: [0.05, 0.05, 0.08],
                },
                pose: pose_from_xyz([0.5, 0.0, 0.04]),
                movable: true,
                mass: 0.1,
                friction: 0.9,
            }],
        }
    }

    #[test]
    fn a_block_between_the_pads_is_held_and_one_beside_them_is_not() {
        let robot = Robot::panda().unwrap();
        let sim = SimWorld::new(&one_block(), &Physics::default());
        let gap = FingerGap::new(&robot, 0.05).unwrap();
        let down = |x: f64| pose_from_xyz_rpy([x, 0.0, 0.065], [PI, 0.0, 0.0]);
        assert!(gap.holds(&sim, &down(0.5), 0));
        assert!(gap.holds(&sim, &down(0.52), 0));
        assert!(!gap.holds(&sim, &down(0.56), 0));
        let above = pose_from_xyz_rpy([0.5, 0.0, 0.2], [PI, 0.0, 0.0]);
        assert!(!gap.holds(&sim, &above, 0));
    }

    #[test]
    fn a_held_object_follows_the_tcp_and_falls_when_released() {
        let mut sim = SimWorld::new(&one_block(), &Physics::default());
        let tcp = pose_from_xyz_rpy([0.5, 0.0, 0.065], [PI, 0.0, 0.0]);
        let held = Held::attach(&mut sim, 0, &tcp);
        let lifted = pose_from_xyz([0.0, 0.0, 0.1]) * tcp;
        for _ in 0..24 {
            held.follow(&mut sim, &lifted);
            sim.step();
        }
        let p = sim.object_pose(0);
        assert!(position_distance(&p, &pose_from_xyz([0.5, 0.0, 0.14])) < 1e-5);
        held.release(&mut sim);
        for _ in 0..240 {
            sim.step();
        }
        assert!(sim.object_pose(0).translation.z < 0.0, "no floor: it falls");
    }
}
