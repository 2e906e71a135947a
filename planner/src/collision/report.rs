//! Every collision of one configuration, and how close each obstacle is: what `akl robot
//! check` prints. The planner stops at the first collision ([`Checker::check`]); this goes on
//! to list them all, with the same model, margins and rules.

use super::checker::Checker;
use crate::contact_rules::{self, Allowances};
use crate::parry_convert;
use serde::Serialize;

/// Two things in collision: two links of the robot, or a link and a world object.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Contact {
    /// The robot link.
    pub link: String,
    /// The other link, for a self collision.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub other_link: Option<String>,
    /// The world object, for a collision with the world.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
}

/// How close the robot comes to one world object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Clearance {
    /// The object.
    pub object: String,
    /// Distance from the robot's collision model (without margins) to it (metres; 0 when
    /// they touch or overlap).
    pub distance: f64,
    /// The link that comes closest.
    pub link: String,
    /// Whether the rules leave this link–object pair unchecked (links standing on the object
    /// the robot is mounted on).
    pub unchecked: bool,
}

/// The result of checking one configuration in full.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckReport {
    /// Every colliding pair, under the margins in use.
    pub collisions: Vec<Contact>,
    /// The least distance to each world object.
    pub clearances: Vec<Clearance>,
}

impl Checker<'_> {
    /// Every collision of configuration `q` (within the joint limits is not checked here) with
    /// gripper opening `width`, holding nothing, and the distance to each object.
    pub fn report(&self, q: &[f64], width: f64) -> CheckReport {
        let links = self.robot.links();
        let (_, placed_bodies) = self.placements(q, width);
        let model = self.model;
        let bodies = &model.bodies;
        let mut collisions = Vec::new();
        let seen = |c: Contact, list: &mut Vec<Contact>| {
            if !list.contains(&c) {
                list.push(c);
            }
        };
        for &(i, j) in &model.self_pairs {
            let (ba, bb) = (&bodies[i], &bodies[j]);
            if parry_convert::intersects(
                &ba.self_shape,
                &placed_bodies[i].pose,
                &bb.self_shape,
                &placed_bodies[j].pose,
            ) {
                seen(
                    Contact {
                        link: links[ba.link].name.clone(),
                        other_link: Some(links[bb.link].name.clone()),
                        object: None,
                    },
                    &mut collisions,
                );
            }
        }
        let allow = Allowances::default();
        let mut clearances: Vec<Clearance> = Vec::new();
        for o in &self.scene.obstacles {
            let mut nearest: Option<Clearance> = None;
            for (b, p) in bodies.iter().zip(&placed_bodies) {
                let role = model.role(b);
                let unchecked =
                    contact_rules::link_may_touch(role, &o.name, None, self.scene.mount(), &allow);
                let margin = model.margins.world(b.group);
                if !unchecked
                    && parry_convert::intersects(&b.world_shape, &p.pose, &o.shape, &o.pose)
                {
                    seen(
                        Contact {
                            link: links[b.link].name.clone(),
                            other_link: None,
                            object: Some(o.name.clone()),
                        },
                        &mut collisions,
                    );
                }
                // The grown shape's distance plus its margin; when the grown shape overlaps,
                // the margin less how deep it goes.
                let grown = parry_convert::distance(&b.world_shape, &p.pose, &o.shape, &o.pose)
                    .unwrap_or(0.0);
                let distance = if grown > 0.0 {
                    grown + margin
                } else {
                    let depth =
                        parry_convert::penetration(&b.world_shape, &p.pose, &o.shape, &o.pose)
                            .unwrap_or(margin);
                    (margin - depth).max(0.0)
                };
                // Checked pairs first: an unchecked mount link resting on the table does not
                // hide how close the checked ones come.
                let closer = nearest
                    .as_ref()
                    .is_none_or(|n| (unchecked, distance) < (n.unchecked, n.distance));
                if closer {
                    nearest = Some(Clearance {
                        object: o.name.clone(),
                        distance,
                        link: links[b.link].name.clone(),
                        unchecked,
                    });
                }
            }
            clearances.extend(nearest);
        }
        CheckReport {
            collisions,
            clearances,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::collision::{Checker, RobotCollision, Scene};
    use crate::contact_rules::Allowances;
    use crate::Robot;
    use rand::{Rng, SeedableRng};

    /// The full report and the planner's first-hit check agree on every configuration: the
    /// report is free exactly when the check finds nothing, and its pairs include the hit.
    #[test]
    fn the_report_agrees_with_the_planners_check() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let world = akl_scene::builtin::task("assembly").unwrap().unwrap().world;
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let allow = Allowances::default();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut free, mut hit) = (0, 0);
        for _ in 0..2_000 {
            let q: Vec<f64> = robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            let width = rng.gen_range(0.0..robot.open_width());
            let first = checker.check(&q, width, None, &allow);
            let report = checker.report(&q, width);
            assert_eq!(
                first.is_none(),
                report.collisions.is_empty(),
                "{q:?}: {first:?} against {:?}",
                report.collisions
            );
            if first.is_some() {
                hit += 1;
            } else {
                free += 1;
            }
            for c in &report.clearances {
                assert!(c.distance >= 0.0 && c.distance.is_finite(), "{c:?}");
            }
        }
        // Both kinds were seen.
        assert!(free > 100 && hit > 100, "{free} free, {hit} in collision");
    }
}
