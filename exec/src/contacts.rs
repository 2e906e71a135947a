//! Contact tracking: after every step, the contacts that involve the arm or the held object,
//! sorted into expected ones (what the step manipulates) and collisions.
//!
//! Expected, and nothing else:
//! - the mount links (robot base) with the object the robot stands on;
//! - the hand links with the held object;
//! - the hand links and the held object with what the current plan segment allows (the
//!   object being grasped or just released; the support a held object leaves or is placed
//!   on), see [`akl_planner::Segment::allowed`].

use crate::world::{Owner, SimWorld};
use akl_planner::collision::{Allowances, Scene};
use akl_planner::Robot;
use akl_scene::World;
use serde::Serialize;

/// Penetration (metres) beyond which two shapes count as touching. A tenth of a millimetre:
/// far below the clearances the planner keeps (at least 1 mm), above single-precision noise.
pub const TOUCH_DEPTH: f64 = 1e-4;

/// Which robot links are hand or mount links, and what the robot stands on.
#[derive(Debug, Clone)]
pub struct ContactRules {
    link_names: Vec<String>,
    hand: Vec<bool>,
    mount: Vec<bool>,
    mount_object: Option<usize>,
}

impl ContactRules {
    /// The rules for `robot` standing in `world` (objects in the simulation's order).
    pub fn new(robot: &Robot, world: &World) -> ContactRules {
        let n = robot.links().len();
        let flags = |indices: &[usize]| {
            let mut v = vec![false; n];
            for &i in indices {
                v[i] = true;
            }
            v
        };
        let scene = Scene::new(world, &[]);
        ContactRules {
            link_names: robot.links().iter().map(|l| l.name.clone()).collect(),
            hand: flags(robot.hand_links()),
            mount: flags(robot.mount_links()),
            mount_object: scene
                .mount()
                .and_then(|m| world.objects.iter().position(|o| o.name == m)),
        }
    }
}

/// A collision: two things touched that should not have.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Collision {
    /// A robot link, or `held <object>`.
    pub a: String,
    /// The object it touched (or the link, for a held object).
    pub b: String,
    /// Simulated time of the first touch (seconds).
    pub t: f64,
    /// Deepest penetration seen (metres).
    pub depth: f64,
    /// The plan segment running at the first touch, e.g. `free to keyframe 2`.
    pub during: String,
}

/// The collisions of one run, one entry per pair of things.
#[derive(Debug, Clone, Default)]
pub struct ContactLog {
    collisions: Vec<Collision>,
}

impl ContactLog {
    /// Scans the contacts of the last step at time `t`, with `held` the object in the hand
    /// and `allowed` the contacts the running segment (`during`) expects.
    pub fn scan(
        &mut self,
        sim: &SimWorld,
        rules: &ContactRules,
        held: Option<usize>,
        allowed: &Allowances,
        t: f64,
        during: &str,
    ) {
        for pair in sim.physics.narrow_phase.contact_pairs() {
            let Some((_, deepest)) = pair.find_deepest_contact() else {
                continue;
            };
            let depth = -f64::from(deepest.dist);
            if depth <= TOUCH_DEPTH {
                continue;
            }
            let (Some(a), Some(b)) = (sim.owner(pair.collider1), sim.owner(pair.collider2)) else {
                continue;
            };
            if let Some((a, b)) = self.classify(sim, rules, held, allowed, a, b) {
                self.record(a, b, t, depth, during);
            }
        }
    }

    /// The names of a pair that collides, or `None` for an expected or unwatched contact.
    fn classify(
        &self,
        sim: &SimWorld,
        rules: &ContactRules,
        held: Option<usize>,
        allowed: &Allowances,
        a: Owner,
        b: Owner,
    ) -> Option<(String, String)> {
        let name = |i: usize| sim.objects[i].name.clone();
        let may = |list: &[String], i: usize| list.iter().any(|n| *n == sim.objects[i].name);
        match (a, b) {
            (Owner::Link(l), Owner::Object(o)) | (Owner::Object(o), Owner::Link(l)) => {
                let hand = rules.hand.get(l).copied().unwrap_or(false);
                let mount = rules.mount.get(l).copied().unwrap_or(false);
                let expected = (mount && rules.mount_object == Some(o))
                    || (hand && (held == Some(o) || may(&allowed.hand_may_touch, o)));
                let link = rules.link_names.get(l).cloned().unwrap_or_default();
                match (expected, held == Some(o)) {
                    (true, _) => None,
                    (false, true) => Some((format!("held {}", name(o)), link)),
                    (false, false) => Some((link, name(o))),
                }
            }
            (Owner::Object(x), Owner::Object(y)) => {
                let (h, other) = match held {
                    Some(h) if h == x => (h, y),
                    Some(h) if h == y => (h, x),
                    _ => return None,
                };
                (!may(&allowed.held_may_touch, other))
                    .then(|| (format!("held {}", name(h)), name(other)))
            }
            (Owner::Link(_), Owner::Link(_)) => None,
        }
    }

    fn record(&mut self, a: String, b: String, t: f64, depth: f64, during: &str) {
        match self
            .collisions
            .iter_mut()
            .find(|c| (c.a == a && c.b == b) || (c.a == b && c.b == a))
        {
            Some(c) => c.depth = c.depth.max(depth),
            None => self.collisions.push(Collision {
                a,
                b,
                t,
                depth,
                during: during.to_string(),
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
    use crate::arm::Arm;
    use crate::world::Physics;
    use akl_tsr::Pose;

    fn ready_arm(task: &str) -> (Robot, SimWorld, Arm, ContactRules) {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task(task).unwrap().unwrap();
        let mut sim = SimWorld::new(&task.world, &Physics::default());
        let arm = Arm::new(&mut sim, &robot, Pose::identity(), robot.ready(), 0.08);
        let rules = ContactRules::new(&robot, &task.world);
        (robot, sim, arm, rules)
    }

    #[test]
    fn the_base_on_the_table_is_expected() {
        let (_, mut sim, _, rules) = ready_arm("inspection");
        let mut log = ContactLog::default();
        for k in 0..10 {
            sim.step();
            log.scan(&sim, &rules, None, &Allowances::default(), k as f64, "test");
        }
        assert!(log.collisions().is_empty(), "{:?}", log.collisions());
    }

    #[test]
    fn a_hand_pushed_into_a_shelf_collides_and_names_both() {
        let (robot, mut sim, mut arm, rules) = ready_arm("inspection");
        let shelf =
            akl_tsr::pose::pose_from_xyz_rpy([0.53, 0.43, 0.12], [std::f64::consts::PI, 0.0, 0.0]);
        let q = robot.ik(&shelf, robot.ready()).unwrap();
        let mut log = ContactLog::default();
        for k in 0..5 {
            arm.drive(&mut sim, &robot, &q, 0.08);
            sim.step();
            log.scan(&sim, &rules, None, &Allowances::default(), k as f64, "test");
        }
        let c = &log.collisions()[0];
        assert!(c.b == "shelf_1" && c.a.starts_with("panda_"), "{c:?}");
        let mut pairs: Vec<(&str, &str)> = log
            .collisions()
            .iter()
            .map(|c| (c.a.as_str(), c.b.as_str()))
            .collect();
        let n = pairs.len();
        pairs.sort();
        pairs.dedup();
        assert_eq!(pairs.len(), n, "one entry per pair");
        let allowed = Allowances {
            hand_may_touch: vec!["shelf_1".into()],
            held_may_touch: Vec::new(),
        };
        let mut lenient = ContactLog::default();
        lenient.scan(&sim, &rules, None, &allowed, 0.0, "test");
        assert!(lenient.collisions().iter().all(|c| !robot
            .hand_links()
            .iter()
            .any(|&h| robot.links()[h].name == c.a)));
    }
}
