//! The task's world in rapier3d: furniture as fixed bodies, movable objects as dynamic bodies
//! with their mass and friction, gravity along −z, a fixed time step.

use crate::convert::{from_sim, object_colliders, to_sim, vector_from_sim};
use crate::exact_depth::ExactShapes;
use akl_planner::collision::ExactShape;
use akl_scene::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use rapier3d::prelude::{
    ActiveCollisionTypes, ColliderBuilder, ColliderHandle, Group, InteractionGroups,
    InteractionTestMode, PairFilterContext, PhysicsHooks, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle, SolverFlags, Vector,
};

/// Collision group of furniture (fixed objects).
pub(crate) const FURNITURE: Group = Group::GROUP_1;
/// Collision group of movable objects (held or not).
pub(crate) const OBJECTS: Group = Group::GROUP_2;
/// Collision group of the robot's links; links never collide with each other in the
/// simulation (the plan is checked for self-collision, and neighbouring links' models overlap).
pub(crate) const ARM: Group = Group::GROUP_3;
/// Collision group of the colliders that show the robot an object's own shape, where the
/// object's collider holds rest aids besides ([`crate::convert::object_colliders`]).
pub(crate) const OWN_SHAPES: Group = Group::GROUP_4;

/// The collision groups of a robot link's colliders: it meets furniture and objects (their own
/// shapes), never another link.
pub(crate) fn link_groups() -> InteractionGroups {
    InteractionGroups::new(
        ARM,
        FURNITURE | OBJECTS | OWN_SHAPES,
        InteractionTestMode::And,
    )
}

/// Whether an object moving at `linear` m/s and `angular` rad/s is at rest for the rest check
/// with `max_speed`.
pub(crate) fn resting(linear: f64, angular: f64, max_speed: f64) -> bool {
    linear <= max_speed && angular <= 10.0 * max_speed
}

/// Simulation settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Physics {
    /// Fixed time step (seconds).
    pub dt: f64,
    /// Constraint solver iterations per step.
    pub solver_iterations: usize,
}

impl Default for Physics {
    /// 1/240 s: at the Panda's top TCP speeds (about 1 m/s) a link moves 4 mm per step, less
    /// than the 5 mm hand margin the planner keeps, so no contact is stepped over.
    fn default() -> Self {
        Physics {
            dt: 1.0 / 240.0,
            solver_iterations: 4,
        }
    }
}

/// What a collider belongs to, stored in its `user_data`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Owner {
    /// The scene object with this index in [`SimWorld::objects`].
    Object(usize),
    /// The robot link with this index in the robot's link list.
    Link(usize),
}

const LINK_TAG: u128 = 1 << 64;

impl Owner {
    /// The value stored in a collider's `user_data`.
    pub(crate) fn to_user_data(self) -> u128 {
        match self {
            Owner::Object(i) => i as u128,
            Owner::Link(i) => LINK_TAG | i as u128,
        }
    }

    /// The owner encoded by [`Owner::to_user_data`].
    pub(crate) fn from_user_data(data: u128) -> Owner {
        if data & LINK_TAG != 0 {
            Owner::Link((data & !LINK_TAG) as usize)
        } else {
            Owner::Object(data as usize)
        }
    }
}

/// A scene object in the simulation.
#[derive(Debug, Clone)]
pub(crate) struct SimObject {
    /// Its name in the task.
    pub name: String,
    /// Whether it is dynamic (movable) or fixed (furniture).
    pub movable: bool,
    /// Its body.
    pub body: RigidBodyHandle,
}

/// Pairs of a robot link and an object whose contacts the simulation does not compute: the
/// pads and the object welded between them, while it is (the weld then carries the whole load,
/// so its force is what friction must hold). Only colliders with
/// `ActiveHooks::FILTER_CONTACT_PAIRS` are asked.
#[derive(Debug, Clone, Default)]
struct UnsolvedPairs {
    pairs: Vec<(usize, usize)>,
}

impl PhysicsHooks for UnsolvedPairs {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        let owner = |c| {
            context
                .colliders
                .get(c)
                .map(|c| Owner::from_user_data(c.user_data))
        };
        let skipped = match (owner(context.collider1)?, owner(context.collider2)?) {
            (Owner::Link(l), Owner::Object(o)) | (Owner::Object(o), Owner::Link(l)) => {
                self.pairs.contains(&(l, o))
            }
            _ => false,
        };
        (!skipped).then_some(SolverFlags::COMPUTE_RIGID_IMPULSES)
    }
}

/// A rapier world built from an AKL [`World`].
pub struct SimWorld {
    /// The rapier state; exposed so the arm, grasp and contact modules can reach its parts.
    pub(crate) physics: PhysicsWorld,
    /// The scene objects, in the task's order.
    pub(crate) objects: Vec<SimObject>,
    /// The exact shape behind each collider, to confirm deep contact readings.
    pub(crate) exact: ExactShapes,
    template: World,
    unsolved: UnsolvedPairs,
    time: f64,
    dt: f64,
}

impl SimWorld {
    /// Builds the simulation of `world`: fixed furniture, dynamic movable objects.
    pub fn new(world: &World, settings: &Physics) -> SimWorld {
        let mut physics = PhysicsWorld::new();
        physics.gravity = Vector::new(0.0, 0.0, -9.81);
        let p = &mut physics.integration_parameters;
        p.dt = settings.dt as f32;
        p.num_solver_iterations = settings.solver_iterations;
        // Objects are a few centimetres: scale rapier's tolerances (slop, prediction) to them.
        p.length_unit = 0.1;
        // Contact distances are read to detect collisions: never let them go stale.
        p.contact_recycling = false;
        // Contacts between two moving bodies four times stiffer than rapier's default (120 Hz);
        // against fixed bodies rapier's default, 60 Hz, a quarter of the step rate. Four times
        // that (the step rate itself) pumped energy into a bottle set down 0.04 rad tilted on a
        // mat: its wobble grew until it was still rocking at 2 rad/s after 2 s of settling, or
        // fell (learned bottles spec, 174 of 200 sampled-goal trials passed; at 60 Hz 200). At
        // 60 Hz the pipe lying on its rail sinks 0.11 mm into it (0.01 mm at 240 Hz), well
        // within the 1 mm the assembly spec allows around its grasp.
        p.contact_softness.natural_frequency *= 4.0;
        let mut objects = Vec::with_capacity(world.objects.len());
        let mut exact = ExactShapes::default();
        for (i, o) in world.objects.iter().enumerate() {
            let body = if o.movable {
                RigidBodyBuilder::dynamic()
            } else {
                RigidBodyBuilder::fixed()
            }
            .pose(to_sim(&o.pose))
            .build();
            let body = physics.bodies.insert(body);
            let (membership, filter, types) = if o.movable {
                (OBJECTS, Group::ALL, ActiveCollisionTypes::all())
            } else {
                (FURNITURE, ARM | OBJECTS, ActiveCollisionTypes::default())
            };
            // Rest aids are for furniture and objects; the robot meets the object's own shape,
            // in a second, massless collider.
            let (collider, own) = object_colliders(&o.shape, &Pose::identity());
            let filter = if own.is_some() {
                filter.difference(ARM)
            } else {
                filter
            };
            // Friction, restitution, groups and owner, alike for both of an object's colliders.
            let finish = |c: ColliderBuilder, groups, types| {
                c.friction(o.friction as f32)
                    .restitution(0.0)
                    .collision_groups(groups)
                    .active_collision_types(types)
                    .user_data(Owner::Object(i).to_user_data())
            };
            let world_groups = InteractionGroups::new(membership, filter, InteractionTestMode::And);
            let mut collider = finish(collider, world_groups, types);
            if o.movable {
                collider = collider.mass(o.mass as f32);
            }
            let exact_shape = ExactShape::of_object(&o.shape);
            let handle = physics
                .colliders
                .insert_with_parent(collider, body, &mut physics.bodies);
            exact.insert(handle, exact_shape.clone(), Pose::identity());
            if let Some(own) = own {
                let robot_groups =
                    InteractionGroups::new(OWN_SHAPES, ARM, InteractionTestMode::And);
                let own = finish(own.density(0.0), robot_groups, ActiveCollisionTypes::all());
                let handle = physics
                    .colliders
                    .insert_with_parent(own, body, &mut physics.bodies);
                exact.insert(handle, exact_shape, Pose::identity());
            }
            objects.push(SimObject {
                name: o.name.clone(),
                movable: o.movable,
                body,
            });
        }
        SimWorld {
            physics,
            objects,
            exact,
            template: world.clone(),
            unsolved: UnsolvedPairs::default(),
            time: 0.0,
            dt: settings.dt,
        }
    }

    /// Advances the simulation by one time step.
    pub fn step(&mut self) {
        self.physics.step_with_events(&self.unsolved, &());
        self.time += self.dt;
    }

    /// Simulated time since the start (seconds).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The fixed time step (seconds).
    pub(crate) fn dt(&self) -> f64 {
        self.dt
    }

    /// Stops (`true`) or resumes computing the contacts of robot link `link` with object
    /// `object`.
    pub(crate) fn set_unsolved(&mut self, link: usize, object: usize, unsolved: bool) {
        let pair = (link, object);
        self.unsolved.pairs.retain(|p| *p != pair);
        if unsolved {
            self.unsolved.pairs.push(pair);
        }
    }

    /// The substeps rapier solves a step in (its solver iterations): a joint's impulses are
    /// those of the last substep, a contact's the step's total.
    pub(crate) fn substeps(&self) -> usize {
        self.physics
            .integration_parameters
            .num_solver_iterations
            .max(1)
    }

    /// Index of the object named `name`.
    pub(crate) fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }

    /// The current world pose of object `i`.
    pub fn object_pose(&self, i: usize) -> Pose {
        from_sim(self.physics.bodies[self.objects[i].body].position())
    }

    /// Moves object `i` to `pose` at once, keeping its velocity (a squeeze seating it between
    /// the pads).
    pub(crate) fn set_object_pose(&mut self, i: usize, pose: &Pose) {
        let body = self.objects[i].body;
        if let Some(b) = self.physics.bodies.get_mut(body) {
            b.set_position(crate::convert::to_sim(pose), true);
        }
    }

    /// The linear and angular speed of object `i` (m/s, rad/s).
    pub fn object_speed(&self, i: usize) -> (f64, f64) {
        let body = &self.physics.bodies[self.objects[i].body];
        let v: Vector3<f64> = vector_from_sim(body.linvel());
        let w: Vector3<f64> = vector_from_sim(body.angvel());
        (v.norm(), w.norm())
    }

    /// The AKL world as it stands now: the task's world with every object at its simulated pose.
    pub(crate) fn snapshot(&self) -> World {
        let mut world = self.template.clone();
        for (i, o) in world.objects.iter_mut().enumerate() {
            o.pose = self.object_pose(i);
        }
        world
    }

    /// The world the simulation was built from.
    pub(crate) fn template(&self) -> &World {
        &self.template
    }

    /// Who owns a collider.
    pub(crate) fn owner(&self, collider: ColliderHandle) -> Option<Owner> {
        self.physics
            .colliders
            .get(collider)
            .map(|c| Owner::from_user_data(c.user_data))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::position_distance;

    #[test]
    fn owners_survive_user_data() {
        for o in [
            Owner::Object(0),
            Owner::Object(7),
            Owner::Link(0),
            Owner::Link(12),
        ] {
            assert_eq!(Owner::from_user_data(o.to_user_data()), o);
        }
    }

    #[test]
    fn objects_rest_where_the_task_puts_them() {
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let mut sim = SimWorld::new(&task.world, &Physics::default());
        for _ in 0..240 {
            sim.step();
        }
        let after = sim.snapshot();
        for (a, b) in after.objects.iter().zip(&task.world.objects) {
            assert!(
                position_distance(&a.pose, &b.pose) < 3e-4,
                "{} moved {:.4} m",
                a.name,
                position_distance(&a.pose, &b.pose)
            );
        }
        assert!((sim.time() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_lying_pipe_stays_put() {
        let task = akl_scene::builtin::task("assembly").unwrap().unwrap();
        let mut sim = SimWorld::new(&task.world, &Physics::default());
        for _ in 0..480 {
            sim.step();
        }
        let pipe = sim.object_index("pipe").unwrap();
        let nominal = task.world.object("pipe").unwrap().pose;
        let d = position_distance(&sim.object_pose(pipe), &nominal);
        assert!(d < 3e-4, "the pipe moved {d:.5} m");
    }
}
