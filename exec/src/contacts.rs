//! Contact verdicts: after every step, the contacts of the arm and of the object in the hand,
//! judged by the shared rules of [`akl_planner::contact_rules`] and by limits on how deep and
//! how hard an allowed contact may be.
//!
//! - The base's links and what the robot stands on are fastened together: not judged.
//! - An allowed contact (the pads on the object being grasped, the held object on its support
//!   at a placement) is a collision when it penetrates deeper
//!   than [`ContactLimits::max_depth`] or pushes harder than [`ContactLimits::max_force`].
//! - The held object brushing the fixture it is being inserted into
//!   ([`contact_rules::held_may_brush`]) is a collision when it penetrates deeper than
//!   [`ContactLimits::max_brush_depth`] or pushes harder than [`ContactLimits::max_brush_force`]:
//!   a compliant insertion slides along the walls, a jam pushes into them.
//! - Any other contact of the arm or the held object is a collision as soon as it penetrates
//!   deeper than [`ContactLimits::touch_depth`] or pushes at all ([`ContactLimits::touch_force`]).
//!
//! A depth beyond a limit is rapier's single-precision reading confirmed on the exact shapes
//! ([`crate::exact_depth`]). Forces are those kept up over [`SUSTAIN_STEPS`] steps, as a
//! force sensor's filter reports them: the single-step impulse of a contact being made is not
//! a push. Contacts between objects that nobody holds are physics, not verdicts.

use crate::world::{Owner, SimWorld};
use akl_planner::collision::Scene;
use akl_planner::contact_rules::Allowances;
use akl_planner::contact_rules::{self, LinkRole};
use akl_planner::Robot;
use akl_scene::World;
use rapier3d::prelude::ColliderHandle;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// How deep and how hard contacts may be.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactLimits {
    /// Deepest penetration of an allowed contact (metres).
    pub max_depth: f64,
    /// Largest force of an allowed contact (N), but for the pads on what they grasp.
    pub max_force: f64,
    /// Largest force of the hand on what it grasps (N): the hand's own squeeze.
    pub max_grip_force: f64,
    /// Deepest penetration of the held object brushing a fixture it is inserted into (metres).
    pub max_brush_depth: f64,
    /// Largest force of the held object brushing a fixture it is inserted into (N).
    pub max_brush_force: f64,
    /// Penetration beyond which any other contact counts (metres).
    pub touch_depth: f64,
    /// Force beyond which any other contact counts (N).
    pub touch_force: f64,
}

impl Default for ContactLimits {
    /// 2 mm for allowed contacts; 30 N for the held object on a support (the ground truths'
    /// placements peak well below, their objects weighing 2–3 N and set down at rest, while a
    /// placement pressed 2 cm into its support exceeds 100 N); the Franka Hand's largest force,
    /// 140 N, for the hand on what it grasps (the pads squeeze with 70 N; more can only come
    /// from the arm pushing the hand into it); for a held object brushing the fixture it is
    /// inserted into, 1 mm (the task format's contact tolerance) and 20 N: the Cartesian
    /// contact force above which the Panda's collision reflex stops a motion in libfranka's
    /// example settings (`Robot::setCollisionBehavior`, upper force thresholds 20 N along x, y
    /// and z), so a compliant insertion on the real arm goes on below it and stops above it —
    /// fixed from that source before any insertion was measured; 0.1 mm and 0.5 N for any other
    /// contact: above single-precision noise and resting contacts' jitter, far below any
    /// clearance the planner keeps.
    fn default() -> Self {
        ContactLimits {
            max_depth: 0.002,
            max_force: 30.0,
            max_grip_force: crate::arm::FRANKA_HAND_MAX_FORCE,
            max_brush_depth: 0.001,
            max_brush_force: 20.0,
            touch_depth: 1e-4,
            touch_force: 0.5,
        }
    }
}

/// The contact role of each robot link, and what the robot stands on.
#[derive(Debug, Clone)]
pub(crate) struct ContactRoles {
    link_names: Vec<String>,
    roles: Vec<LinkRole>,
    mount: Option<String>,
}

impl ContactRoles {
    /// The roles of `robot`'s links, standing in `world`.
    pub(crate) fn new(robot: &Robot, world: &World) -> ContactRoles {
        let roles = (0..robot.links().len())
            .map(|i| LinkRole {
                hand: robot.hand_links().contains(&i),
                mount: robot.mount_links().contains(&i),
            })
            .collect();
        ContactRoles {
            link_names: robot.links().iter().map(|l| l.name.clone()).collect(),
            roles,
            mount: Scene::new(world, &[]).mount().map(String::from),
        }
    }
}

/// A collision: two things touched that should not have, or too deep or too hard.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Collision {
    /// A robot link, or `held <object>`.
    pub a: String,
    /// The object it touched.
    pub b: String,
    /// Simulated time of the first offending contact (seconds).
    pub t: f64,
    /// Deepest penetration seen (metres).
    pub depth: f64,
    /// Largest force seen (N).
    pub force: f64,
    /// Whether the rules allow the contact (then it broke a limit).
    pub allowed: bool,
    /// The plan step running at the first offending contact, e.g. `free motion to keyframe 2`.
    pub during: String,
    /// The keyframe that step leads to (`None` while settling).
    pub keyframe: Option<usize>,
}

impl Collision {
    /// The collision in words.
    pub fn describe(&self) -> String {
        let how = if self.allowed {
            "pressed against"
        } else {
            "touched"
        };
        format!(
            "{} {how} {} at {:.2} s ({}, {:.1} mm deep, {:.0} N)",
            self.a,
            self.b,
            self.t,
            self.during,
            self.depth * 1e3,
            self.force
        )
    }
}

/// The extreme of a contact measure over a run, and where it happened.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Extreme {
    /// The value (metres or newtons).
    pub value: f64,
    /// The pair, e.g. `fer_leftfinger–part`.
    pub pair: String,
    /// When (simulated seconds).
    pub t: f64,
}

impl Extreme {
    fn update(&mut self, value: f64, a: &str, b: &str, t: f64) {
        if value > self.value {
            *self = Extreme {
                value,
                pair: format!("{a}–{b}"),
                t,
            };
        }
    }
}

/// One contact of the arm or the held object, as a trace shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPoint {
    /// World position (metres).
    pub point: [f64; 3],
    /// Force (N).
    pub force: f64,
    /// Whether it is a collision.
    pub collision: bool,
}

/// What the rules say of one contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Verdict {
    /// The hand on what it grasps, holds or releases.
    Grip,
    /// Another allowed contact (the held object on a support).
    Allowed,
    /// The held object brushing a fixture it is inserted into.
    Brush,
    /// Not allowed at all.
    Forbidden,
}

/// What one step may touch: the plan step's allowances, its name, and the object held.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepContext<'a> {
    /// The contacts the step allows.
    pub allow: &'a Allowances,
    /// The object in the hand (index), if any.
    pub held: Option<usize>,
    /// The step, in words.
    pub during: &'a str,
    /// The keyframe the step's segment leads to (`None` while settling).
    pub keyframe: Option<usize>,
    /// Simulated time.
    pub t: f64,
}

/// Whether a contact between `a` and `b` is judged: one of them is a robot link or the object
/// in the hand.
fn watched(a: Owner, b: Owner, held: Option<usize>) -> bool {
    match (a, b) {
        (Owner::Link(_), _) | (_, Owner::Link(_)) => true,
        (Owner::Object(x), Owner::Object(y)) => held.is_some_and(|h| h == x || h == y),
    }
}

/// Steps over which a force must be kept up to count: 3 steps (12.5 ms at 240 Hz).
pub(crate) const SUSTAIN_STEPS: usize = 3;

/// The contact verdicts and extremes of one run.
#[derive(Debug, Clone, Default)]
pub struct ContactLog {
    collisions: Vec<Collision>,
    /// The forces of the last steps, by collider pair.
    recent: HashMap<(ColliderHandle, ColliderHandle), [f64; SUSTAIN_STEPS]>,
    /// The map of the step before, kept to be reused.
    spare: HashMap<(ColliderHandle, ColliderHandle), [f64; SUSTAIN_STEPS]>,
    /// Deepest contact of the arm or the held object (metres).
    pub deepest: Extreme,
    /// Largest force of a contact of the arm or the held object (N).
    pub strongest: Extreme,
}

impl ContactLog {
    /// Judges the contacts of the last step; returns each watched contact's point when
    /// `points` is asked for (traces).
    pub(crate) fn scan(
        &mut self,
        sim: &SimWorld,
        roles: &ContactRoles,
        limits: &ContactLimits,
        step: &StepContext,
        mut points: Option<&mut Vec<ContactPoint>>,
    ) {
        let dt = sim.dt();
        let mut recent = std::mem::take(&mut self.spare);
        recent.clear();
        for pair in sim.physics.narrow_phase.contact_pairs() {
            let (Some(a), Some(b)) = (sim.owner(pair.collider1), sim.owner(pair.collider2)) else {
                continue;
            };
            if !watched(a, b, step.held) {
                continue;
            }
            let Some((_, deepest)) = pair.find_deepest_contact() else {
                continue;
            };
            let depth = -f64::from(deepest.dist);
            let impulse_force = f64::from(pair.total_impulse_magnitude()) / dt;
            if depth <= 0.0 && impulse_force <= 0.0 {
                continue;
            }
            let force = self.sustained(pair.collider1, pair.collider2, impulse_force, &mut recent);
            let Some((a, b, verdict)) = self.classify(sim, roles, step, a, b) else {
                continue;
            };
            let allowed = verdict != Verdict::Forbidden;
            let (max_depth, max_force) = match verdict {
                Verdict::Grip => (limits.max_depth, limits.max_grip_force),
                Verdict::Allowed => (limits.max_depth, limits.max_force),
                Verdict::Brush => (limits.max_brush_depth, limits.max_brush_force),
                Verdict::Forbidden => (limits.touch_depth, limits.touch_force),
            };
            // A reading deep enough to offend is measured again on the exact shapes.
            let depth = if depth > max_depth {
                sim.exact
                    .depth(
                        &sim.physics.colliders,
                        &sim.physics.bodies,
                        [pair.collider1, pair.collider2],
                    )
                    .unwrap_or(depth)
            } else {
                depth
            };
            let offending = depth > max_depth || force > max_force;
            if depth > limits.touch_depth || force > limits.touch_force {
                self.deepest.update(depth.max(0.0), &a, &b, step.t);
                self.strongest.update(force, &a, &b, step.t);
            }
            if let Some(points) = points.as_deref_mut() {
                if let Some(c1) = sim.physics.colliders.get(pair.collider1) {
                    let p = c1.position().transform_point(deepest.local_p1);
                    points.push(ContactPoint {
                        point: [f64::from(p.x), f64::from(p.y), f64::from(p.z)],
                        force,
                        collision: offending,
                    });
                }
            }
            if offending {
                self.record(a, b, allowed, step, depth, force);
            }
        }
        self.spare = std::mem::replace(&mut self.recent, recent);
    }

    /// The force a pair has kept up over the last [`SUSTAIN_STEPS`] steps (the smallest of
    /// them): what a force sensor's filter reports, without the one-step impulses of a contact
    /// being made.
    fn sustained(
        &self,
        a: ColliderHandle,
        b: ColliderHandle,
        force: f64,
        recent: &mut HashMap<(ColliderHandle, ColliderHandle), [f64; SUSTAIN_STEPS]>,
    ) -> f64 {
        let mut window = self
            .recent
            .get(&(a, b))
            .copied()
            .unwrap_or([0.0; SUSTAIN_STEPS]);
        window.rotate_left(1);
        window[SUSTAIN_STEPS - 1] = force;
        recent.insert((a, b), window);
        window.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// The names of a watched pair and what the rules say of it; `None` for a pair nobody
    /// holds, and for the base on what it stands on.
    fn classify(
        &self,
        sim: &SimWorld,
        roles: &ContactRoles,
        step: &StepContext,
        a: Owner,
        b: Owner,
    ) -> Option<(String, String, Verdict)> {
        let name = |i: usize| sim.objects[i].name.as_str();
        let held = step.held.map(name);
        match (a, b) {
            (Owner::Link(l), Owner::Object(o)) | (Owner::Object(o), Owner::Link(l)) => {
                let role = roles.roles.get(l).copied().unwrap_or_default();
                if role.mount && roles.mount.as_deref() == Some(name(o)) {
                    // The base is fastened to what it stands on; its model reaches into it.
                    return None;
                }
                let allowed = contact_rules::link_may_touch(
                    role,
                    name(o),
                    held,
                    roles.mount.as_deref(),
                    step.allow,
                );
                let verdict = match (allowed, role.hand) {
                    (false, _) => Verdict::Forbidden,
                    (true, true) => Verdict::Grip,
                    (true, false) => Verdict::Allowed,
                };
                let link = roles.link_names.get(l).cloned().unwrap_or_default();
                Some(if step.held == Some(o) {
                    (format!("held {}", name(o)), link, verdict)
                } else {
                    (link, name(o).to_string(), verdict)
                })
            }
            (Owner::Object(x), Owner::Object(y)) => {
                let (h, other) = match step.held {
                    Some(h) if h == x => (h, y),
                    Some(h) if h == y => (h, x),
                    _ => return None,
                };
                let verdict = if contact_rules::held_may_touch(name(other), step.allow) {
                    Verdict::Allowed
                } else if contact_rules::held_may_brush(name(other), step.allow) {
                    Verdict::Brush
                } else {
                    Verdict::Forbidden
                };
                Some((
                    format!("held {}", name(h)),
                    name(other).to_string(),
                    verdict,
                ))
            }
            (Owner::Link(_), Owner::Link(_)) => None,
        }
    }

    fn record(
        &mut self,
        a: String,
        b: String,
        allowed: bool,
        step: &StepContext,
        depth: f64,
        force: f64,
    ) {
        match self
            .collisions
            .iter_mut()
            .find(|c| (c.a == a && c.b == b) || (c.a == b && c.b == a))
        {
            Some(c) => {
                c.depth = c.depth.max(depth);
                c.force = c.force.max(force);
            }
            None => self.collisions.push(Collision {
                a,
                b,
                t: step.t,
                depth: depth.max(0.0),
                force,
                allowed,
                during: step.during.to_string(),
                keyframe: step.keyframe,
            }),
        }
    }

    /// The collisions, in the order they first happened.
    pub fn collisions(&self) -> &[Collision] {
        &self.collisions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Physics;
    use akl_planner::contact_rules::Step;

    /// pick_place in the simulation, the Panda's contact roles there, and a hand link, an arm
    /// link and a base link.
    fn pick_place() -> (SimWorld, ContactRoles, [usize; 3]) {
        let robot = Robot::panda().unwrap();
        let world = akl_scene::builtin::task("pick_place")
            .unwrap()
            .unwrap()
            .world;
        let sim = SimWorld::new(&world, &Physics::default());
        let roles = ContactRoles::new(&robot, &world);
        let hand = robot.hand_links()[0];
        let base = robot.mount_links()[0];
        let arm = (0..robot.links().len())
            .find(|l| !robot.hand_links().contains(l) && !robot.mount_links().contains(l))
            .unwrap();
        (sim, roles, [hand, arm, base])
    }

    fn context<'a>(allow: &'a Allowances, held: Option<usize>) -> StepContext<'a> {
        StepContext {
            allow,
            held,
            during: "a step",
            keyframe: Some(0),
            t: 1.0,
        }
    }

    /// Each pair gets what `contact_rules` says of it: the hand on what it closes on grips,
    /// the hand on anything else and the arm on anything are forbidden, the held object on
    /// its support is allowed and on a fixture it enters brushes, the base on the table it
    /// stands on and two objects nobody holds are not judged.
    #[test]
    fn contacts_are_classified_by_the_shared_rules() {
        let (sim, roles, [hand, arm, base]) = pick_place();
        let log = ContactLog::default();
        let object = |n: &str| Owner::Object(sim.object_index(n).unwrap());
        let verdict =
            |step: &StepContext, a: Owner, b: Owner| log.classify(&sim, &roles, step, a, b);
        let grasping = Step {
            grasping: Some("block_a"),
            ..Step::default()
        }
        .allowances();
        let reach = context(&grasping, None);
        let hand_name = roles.link_names[hand].clone();
        assert_eq!(
            verdict(&reach, Owner::Link(hand), object("block_a")),
            Some((hand_name.clone(), "block_a".into(), Verdict::Grip))
        );
        assert_eq!(
            verdict(&reach, object("block_b"), Owner::Link(hand)).map(|v| v.2),
            Some(Verdict::Forbidden)
        );
        assert_eq!(
            verdict(&reach, Owner::Link(arm), object("block_a")).map(|v| v.2),
            Some(Verdict::Forbidden)
        );
        assert_eq!(verdict(&reach, Owner::Link(base), object("table")), None);
        assert_eq!(
            verdict(&reach, Owner::Link(base), object("shelf_1")).map(|v| v.2),
            Some(Verdict::Forbidden)
        );
        assert_eq!(verdict(&reach, object("block_a"), object("mat_a")), None);

        let entering = ["shelf_2".to_string()];
        let placing = Step {
            placing_on: Some("mat_a"),
            beneath: Some("shelf_1"),
            entering: &entering,
            ..Step::default()
        }
        .allowances();
        let held = sim.object_index("block_a");
        let place = context(&placing, held);
        assert_eq!(
            verdict(&place, object("mat_a"), object("block_a")),
            Some(("held block_a".into(), "mat_a".into(), Verdict::Allowed))
        );
        assert_eq!(
            verdict(&place, object("block_a"), object("shelf_2")).map(|v| v.2),
            Some(Verdict::Brush)
        );
        assert_eq!(
            verdict(&place, object("block_a"), object("block_b")).map(|v| v.2),
            Some(Verdict::Forbidden)
        );
        // The hand on what it holds, named as the held object's contact.
        assert_eq!(
            verdict(&place, Owner::Link(hand), object("block_a")),
            Some(("held block_a".into(), hand_name, Verdict::Grip))
        );
        assert_eq!(verdict(&place, object("block_b"), object("mat_b")), None);
    }

    /// A pair is one collision however often it offends: first time and step kept, the
    /// deepest and the strongest contact of it.
    #[test]
    fn a_pair_is_recorded_once_with_its_extremes() {
        let allow = Allowances::default();
        let mut log = ContactLog::default();
        let mut step = context(&allow, None);
        log.record(
            "fer_hand".into(),
            "shelf_1".into(),
            false,
            &step,
            0.001,
            3.0,
        );
        step.t = 2.0;
        step.during = "later";
        log.record(
            "shelf_1".into(),
            "fer_hand".into(),
            false,
            &step,
            0.0005,
            9.0,
        );
        log.record(
            "fer_link4".into(),
            "shelf_1".into(),
            false,
            &step,
            0.002,
            1.0,
        );
        let c = log.collisions();
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].t, c[0].during.as_str()), (1.0, "a step"));
        assert_eq!((c[0].depth, c[0].force), (0.001, 9.0));
        assert_eq!(c[1].a, "fer_link4");
        assert!(c[0]
            .describe()
            .contains("fer_hand touched shelf_1 at 1.00 s"));
    }

    #[test]
    fn only_contacts_of_the_arm_or_the_held_object_are_judged() {
        assert!(watched(Owner::Link(3), Owner::Object(0), None));
        assert!(watched(Owner::Object(0), Owner::Link(3), Some(1)));
        // Two objects: only when one of them is in the hand.
        assert!(!watched(Owner::Object(0), Owner::Object(1), None));
        assert!(!watched(Owner::Object(0), Owner::Object(1), Some(2)));
        assert!(watched(Owner::Object(0), Owner::Object(1), Some(1)));
    }

    #[test]
    fn an_extreme_keeps_the_largest_value_and_where_it_was() {
        let mut e = Extreme::default();
        e.update(5.0, "fer_hand", "table", 1.0);
        e.update(3.0, "fer_link5", "shelf", 2.0);
        assert_eq!(
            (e.value, e.pair.as_str(), e.t),
            (5.0, "fer_hand–table", 1.0)
        );
        e.update(7.5, "held part", "scanner_1", 3.0);
        assert_eq!(
            (e.value, e.pair.as_str(), e.t),
            (7.5, "held part–scanner_1", 3.0)
        );
    }

    /// A force counts only once kept up for [`SUSTAIN_STEPS`] steps: a one-step impulse of a
    /// contact being made reads as nothing, a lasting push as its smallest recent value.
    #[test]
    fn a_force_counts_once_it_is_kept_up() {
        let (a, b) = (
            ColliderHandle::from_raw_parts(1, 0),
            ColliderHandle::from_raw_parts(2, 0),
        );
        let mut log = ContactLog::default();
        let step = |log: &mut ContactLog, force: f64| {
            let mut recent = HashMap::new();
            let kept = log.sustained(a, b, force, &mut recent);
            log.recent = recent;
            kept
        };
        assert_eq!(step(&mut log, 500.0), 0.0, "an impulse");
        assert_eq!(step(&mut log, 0.0), 0.0);
        for _ in 0..SUSTAIN_STEPS - 1 {
            assert_eq!(step(&mut log, 40.0), 0.0, "not yet kept up");
        }
        assert_eq!(step(&mut log, 60.0), 40.0, "the smallest of the window");
        assert_eq!(step(&mut log, 60.0), 40.0);
        assert_eq!(step(&mut log, 60.0), 60.0);
    }

    /// Radius (metres) of the bottle the probe tests touch.
    const BOTTLE_RADIUS: f64 = 0.05;

    /// A bottle and a 2 cm cube owned by a robot link whose face stands `gap` metres off the
    /// bottle's side (negative: pressed into it), facing it along a corner of the bottle's rest
    /// prism, and what the last step's contacts say of it, nothing allowed: without `approach`,
    /// one step with the bottle fastened where it stands (so it stays in place); with it, the
    /// cube moving in at `approach` m/s for two steps towards the movable bottle.
    /// `exact_radius` is the radius the bottle's exact shape is given (the reading's
    /// confirmation).
    fn probe(gap: f64, exact_radius: f64, approach: Option<f64>) -> (SimWorld, ContactLog) {
        use crate::convert::to_sim;
        use crate::world::link_groups;
        use akl_planner::collision::ExactShape;
        use akl_scene::{Object, Shape};
        use akl_tsr::pose::pose_from_xyz_rpy;
        use akl_tsr::Pose;
        use rapier3d::prelude::ColliderBuilder;
        use rapier3d::prelude::{ActiveCollisionTypes, RigidBodyBuilder, Vector};
        let shape = |radius| Shape::Cylinder {
            radius,
            length: 0.2,
        };
        let world = World {
            robot_base: Pose::identity(),
            objects: vec![Object {
                name: "bottle".into(),
                shape: shape(BOTTLE_RADIUS),
                pose: Pose::identity(),
                movable: approach.is_some(),
                mass: 0.5,
                friction: 0.5,
            }],
        };
        let mut sim = SimWorld::new(&world, &Physics::default());
        let exact = ExactShape::of_object(&shape(exact_radius));
        let bottle: Vec<_> = sim.physics.colliders.iter().map(|(h, _)| h).collect();
        for h in bottle {
            sim.exact.insert(h, exact.clone(), Pose::identity());
        }
        // The prism's first corner lies at π/24 about z.
        let angle = std::f64::consts::PI / 24.0;
        let centre = BOTTLE_RADIUS + gap + 0.01;
        let pose = pose_from_xyz_rpy(
            [centre * angle.cos(), centre * angle.sin(), 0.0],
            [0.0, 0.0, angle],
        );
        let speed = approach.unwrap_or(0.0);
        let inward = Vector::new(-angle.cos() as f32, -angle.sin() as f32, 0.0) * speed as f32;
        let p = &mut sim.physics;
        let body = p.bodies.insert(
            RigidBodyBuilder::kinematic_velocity_based()
                .pose(to_sim(&pose))
                .linvel(inward)
                .build(),
        );
        let cube = ColliderBuilder::cuboid(0.01, 0.01, 0.01)
            .collision_groups(link_groups())
            .active_collision_types(ActiveCollisionTypes::all())
            .user_data(Owner::Link(0).to_user_data());
        let cube = p.colliders.insert_with_parent(cube, body, &mut p.bodies);
        let size = [0.02; 3];
        let cube_shape = ExactShape::of_element(&akl_planner::Geometry::Box { size });
        sim.exact.insert(cube, cube_shape, Pose::identity());
        for _ in 0..if approach.is_some() { 2 } else { 1 } {
            sim.step();
        }
        let roles = ContactRoles {
            link_names: vec!["probe".into()],
            roles: vec![LinkRole::default()],
            mount: None,
        };
        let allow = Allowances::default();
        let mut log = ContactLog::default();
        log.scan(
            &sim,
            &roles,
            &ContactLimits::default(),
            &context(&allow, None),
            None,
        );
        (sim, log)
    }

    /// The rest prism's corners stand 0.43 mm proud of a 5 cm bottle: a link 0.2 mm off the
    /// bottle, moving in by less than that, reaches into the prism, which must neither push
    /// the bottle nor be judged.
    #[test]
    fn the_robot_never_meets_a_rest_prism() {
        let (sim, log) = probe(0.0002, BOTTLE_RADIUS, Some(0.01));
        assert!(log.collisions().is_empty(), "{:?}", log.collisions());
        let v = sim.physics.bodies[sim.objects[0].body].linvel();
        assert!(v.x.hypot(v.y) < 1e-6, "the bottle was pushed at {v:?}");
    }

    /// The negative control: a link pressed 1 mm into the bottle touches it, and the depth is
    /// the exact one.
    #[test]
    fn a_millimetre_press_is_a_collision() {
        let (_, log) = probe(-0.001, BOTTLE_RADIUS, None);
        let c = log.collisions();
        assert_eq!(c.len(), 1, "{c:?}");
        assert_eq!((c[0].a.as_str(), c[0].b.as_str()), ("probe", "bottle"));
        assert!((c[0].depth - 0.001).abs() < 2e-4, "{}", c[0].depth);
    }

    /// A reading past the limit is judged on the exact shapes: where they are apart (here the
    /// bottle's exact shape is 2 mm thinner than its collider), there is no collision.
    #[test]
    fn a_deep_reading_is_confirmed_on_the_exact_shapes() {
        let (_, log) = probe(-0.001, BOTTLE_RADIUS - 0.002, None);
        assert!(log.collisions().is_empty(), "{:?}", log.collisions());
        let (_, log) = probe(-0.003, BOTTLE_RADIUS - 0.002, None);
        let c = log.collisions();
        assert_eq!(c.len(), 1, "{c:?}");
        assert!((c[0].depth - 0.001).abs() < 2e-4, "{}", c[0].depth);
    }
}
