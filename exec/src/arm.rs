//! The robot in the simulation: one kinematic, position-based body per link with collision
//! geometry, moved each step to the poses forward kinematics gives for the planned joints.
//!
//! Why kinematic bodies and not joint motors: the plan is already collision-checked and timed
//! within the joint limits, and what execution verifies is the spec (grounding, lines, grasps,
//! contacts, goals), not a controller. Motors would add tracking error that says nothing about
//! the spec, and cost solver iterations. A kinematic body still pushes dynamic objects it
//! touches and reports its contacts, which is what verification needs.

use crate::convert::{link_collider, to_sim};
use crate::world::{Owner, SimWorld, ARM, FURNITURE, OBJECTS};
use akl_planner::Robot;
use akl_tsr::Pose;
use rapier3d::pipeline::ActiveHooks;
use rapier3d::prelude::{
    ActiveCollisionTypes, InteractionGroups, InteractionTestMode, RigidBodyBuilder, RigidBodyHandle,
};

/// Friction of the fingers and links against objects (rubber-like finger pads).
pub const LINK_FRICTION: f64 = 1.0;

/// The simulated arm.
pub struct Arm {
    base: Pose,
    /// Rapier body of each robot link that has collision geometry, by link index.
    bodies: Vec<Option<RigidBodyHandle>>,
    /// World pose of every link at the last commanded configuration.
    poses: Vec<Pose>,
    tcp: usize,
}

impl Arm {
    /// Adds `robot`, standing at `base`, to `sim` at configuration `q` with the gripper
    /// opened `width`.
    pub fn new(sim: &mut SimWorld, robot: &Robot, base: Pose, q: &[f64], width: f64) -> Arm {
        let mut arm = Arm {
            base,
            bodies: Vec::with_capacity(robot.links().len()),
            poses: vec![Pose::identity(); robot.links().len()],
            tcp: robot.tcp_link(),
        };
        arm.compute(robot, q, width);
        let mut hand = vec![false; robot.links().len()];
        for &h in robot.hand_links() {
            hand[h] = true;
        }
        let physics = &mut sim.physics;
        for (i, link) in robot.links().iter().enumerate() {
            if link.shapes.is_empty() {
                arm.bodies.push(None);
                continue;
            }
            let body = physics.bodies.insert(
                RigidBodyBuilder::kinematic_position_based()
                    .pose(to_sim(&arm.poses[i]))
                    .build(),
            );
            let hooks = if hand[i] {
                ActiveHooks::FILTER_CONTACT_PAIRS
            } else {
                ActiveHooks::empty()
            };
            for shape in &link.shapes {
                let collider = link_collider(&shape.geometry, &shape.origin)
                    .active_hooks(hooks)
                    .friction(LINK_FRICTION as f32)
                    .restitution(0.0)
                    .collision_groups(InteractionGroups::new(
                        ARM,
                        FURNITURE | OBJECTS,
                        InteractionTestMode::And,
                    ))
                    .active_collision_types(ActiveCollisionTypes::all())
                    .user_data(Owner::Link(i).to_user_data());
                physics
                    .colliders
                    .insert_with_parent(collider, body, &mut physics.bodies);
            }
            arm.bodies.push(Some(body));
        }
        sim.set_hand_links(hand);
        arm
    }

    fn compute(&mut self, robot: &Robot, q: &[f64], width: f64) {
        robot
            .kinematics()
            .link_poses_into(q, width, &mut self.poses);
        for p in &mut self.poses {
            *p = self.base * *p;
        }
    }

    /// Commands the configuration `q` and opening `width` for the end of the next step.
    pub fn drive(&mut self, sim: &mut SimWorld, robot: &Robot, q: &[f64], width: f64) {
        self.compute(robot, q, width);
        for (body, pose) in self.bodies.iter().zip(&self.poses) {
            if let Some(b) = body.and_then(|b| sim.physics.bodies.get_mut(b)) {
                b.set_next_kinematic_position(to_sim(pose));
            }
        }
    }

    /// World pose of every link at the last commanded configuration, in the robot's link order.
    pub fn link_poses(&self) -> &[Pose] {
        &self.poses
    }

    /// World pose of the TCP at the last commanded configuration.
    pub fn tcp(&self) -> Pose {
        self.poses[self.tcp]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convert::from_sim;
    use crate::world::Physics;
    use akl_tsr::pose::position_distance;

    #[test]
    fn links_follow_the_commanded_configuration() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let mut sim = SimWorld::new(&task.world, &Physics::default());
        let ready = robot.ready().to_vec();
        let mut arm = Arm::new(&mut sim, &robot, Pose::identity(), &ready, 0.08);
        let mut q = ready.clone();
        q[0] += 0.3;
        q[3] += 0.2;
        arm.drive(&mut sim, &robot, &q, 0.02);
        sim.step();
        let expected = robot.link_poses(&q, 0.02);
        for (i, b) in arm.bodies.iter().enumerate() {
            if let Some(b) = b {
                let at = from_sim(sim.physics.bodies[*b].position());
                assert!(position_distance(&at, &expected[i]) < 1e-5, "link {i}");
            }
        }
        assert!(position_distance(&arm.tcp(), &robot.tcp_pose(&q)) < 1e-9);
    }
}
