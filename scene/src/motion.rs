//! How randomization moves a task's objects: rigid bodies ("movers") that carry what stands
//! on them, and the relations between objects that no draw can change.

use crate::error::SceneError;
use crate::range::Range;
use crate::task::Task;
use crate::world::World;
use akl_tsr::nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};
use akl_tsr::{Pose, WORLD_FRAME};
use rand::Rng;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// One rigid body of the randomization: an object, or a group of furniture moved as one.
#[derive(Debug, Clone, PartialEq)]
pub struct Mover {
    /// The object's or the group's name (its range is keyed by it).
    pub name: String,
    /// Whether it is a group (rather than one object).
    pub group: bool,
    /// The objects it moves.
    pub members: Vec<String>,
    /// How far it may move relative to its carrier; `None`: not at all.
    pub range: Option<Range>,
    /// Index in [`Motion::movers`] of the mover it stands on; `None`: nothing that moves.
    pub carrier: Option<usize>,
    /// The centre it turns about in the task file's layout: the mean of its members' centres.
    pub pivot: Point3<f64>,
}

/// Every object of a task assigned to exactly one [`Mover`], movers listed so that each comes
/// after the one carrying it (the order in which randomization draws them).
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// The movers in draw order.
    pub movers: Vec<Mover>,
    mover_of: BTreeMap<String, usize>,
}

/// Objects (and possibly the `world` frame) that every randomized layout keeps in one fixed
/// relation to each other, so a keyframe grounded on any of them lands in the same place.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FixedRelation {
    /// The names held together, sorted; `world` when they do not move at all.
    pub members: Vec<String>,
    /// Why, in words.
    pub because: String,
}

/// A rigid body of the randomization before it is ordered: (name, is a group, members).
type Body = (String, bool, Vec<String>);

impl Motion {
    /// How `task`'s randomization moves its objects. A group or object rides on the mover of
    /// what its lowest member stands on in the task file (when that is outside itself). Fails
    /// when movers carry each other in a circle, naming one of them.
    pub fn of(task: &Task) -> Result<Motion, SceneError> {
        let world = &task.world;
        let bodies = bodies(task);
        let carriers = carriers(world, &bodies);
        let depth = depths(&bodies, &carriers)?;
        let mut order: Vec<usize> = (0..bodies.len()).collect();
        order.sort_by(|&a, &b| depth[a].cmp(&depth[b]).then(bodies[a].0.cmp(&bodies[b].0)));
        let mut position = vec![0; bodies.len()];
        for (new, &old) in order.iter().enumerate() {
            position[old] = new;
        }
        let movers: Vec<Mover> = order
            .iter()
            .map(|&old| {
                let (name, group, members) = bodies[old].clone();
                let centres: Vec<Vector3<f64>> = members
                    .iter()
                    .filter_map(|m| world.object(m))
                    .map(|o| o.pose.translation.vector)
                    .collect();
                let pivot = centres.iter().sum::<Vector3<f64>>() / centres.len().max(1) as f64;
                Mover {
                    range: task.randomize.get(&name).copied(),
                    name,
                    group,
                    members,
                    carrier: carriers[old].map(|c| position[c]),
                    pivot: pivot.into(),
                }
            })
            .collect();
        let mover_of = movers
            .iter()
            .enumerate()
            .flat_map(|(i, m)| m.members.iter().map(move |n| (n.clone(), i)))
            .collect();
        Ok(Motion { movers, mover_of })
    }

    /// The mover that moves object `name`.
    pub fn mover_of(&self, name: &str) -> Option<&Mover> {
        self.mover_of.get(name).map(|&i| &self.movers[i])
    }

    /// The name of the mover object `name` stands on, if any moves it.
    pub fn carrier_of(&self, name: &str) -> Option<&str> {
        let mover = self.mover_of(name)?;
        mover.carrier.map(|c| self.movers[c].name.as_str())
    }

    /// Whether randomization can move object `name`: its mover, or a mover carrying it, has
    /// a range that varies.
    pub fn moves(&self, name: &str) -> bool {
        self.mover_of
            .get(name)
            .is_some_and(|&i| self.anchor(i).is_some())
    }

    /// Draws one layout: every mover with a range moved by an offset and turn drawn uniformly
    /// within it, after it has been carried along by its carrier; movers in order, three draws
    /// (x, y, yaw) from `rng` for each that has a range.
    pub fn draw<R: Rng + ?Sized>(&self, nominal: &World, rng: &mut R) -> World {
        let mut placed: Vec<Pose> = Vec::with_capacity(self.movers.len());
        for m in &self.movers {
            let carried = m.carrier.map_or(Pose::identity(), |c| placed[c]);
            let moved = match &m.range {
                None => carried,
                Some(r) => {
                    let offset =
                        carried.rotation * Vector3::new(sample(rng, r.x), sample(rng, r.y), 0.0);
                    let turn =
                        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), sample(rng, r.yaw));
                    let pivot = (carried * m.pivot).coords;
                    Translation3::from(pivot + offset) * turn * Translation3::from(-pivot) * carried
                }
            };
            placed.push(moved);
        }
        let mut world = nominal.clone();
        for o in &mut world.objects {
            if let Some(&i) = self.mover_of.get(&o.name) {
                o.pose = placed[i] * o.pose;
            }
        }
        world
    }

    /// The movers each object's place in a layout depends on: following carriers down from
    /// its own mover past every mover whose range cannot vary, the first one that can; `None`
    /// when nothing that varies moves it.
    fn anchor(&self, mut at: usize) -> Option<usize> {
        loop {
            let m = &self.movers[at];
            if m.range.is_some_and(|r| !r.is_constant()) {
                return Some(at);
            }
            at = m.carrier?;
        }
    }

    /// The sets of names that every layout keeps in one fixed relation (see
    /// [`Task::fixed_relations`]).
    pub fn fixed_relations(&self, world: &World) -> Vec<FixedRelation> {
        let mut sets: BTreeMap<Option<usize>, Vec<String>> = BTreeMap::new();
        sets.entry(None).or_default().push(WORLD_FRAME.to_string());
        for o in &world.objects {
            if let Some(&i) = self.mover_of.get(&o.name) {
                sets.entry(self.anchor(i)).or_default().push(o.name.clone());
            }
        }
        sets.into_iter()
            .filter(|(_, members)| members.len() > 1)
            .map(|(anchor, mut members)| {
                members.sort();
                let because = match anchor.map(|i| &self.movers[i]) {
                    None => "not moved by the randomization".to_string(),
                    Some(m) if m.group => {
                        format!("moved as one body by group `{}`", m.name)
                    }
                    Some(m) => format!(
                        "carried by {} (standing on it without a range of their own)",
                        m.name
                    ),
                };
                FixedRelation { members, because }
            })
            .collect()
    }
}

/// The task's rigid bodies: its groups (by name), then every object in no group (file order).
fn bodies(task: &Task) -> Vec<Body> {
    let grouped: BTreeSet<&str> = task.groups.values().flatten().map(String::as_str).collect();
    let groups = task
        .groups
        .iter()
        .map(|(name, members)| (name.clone(), true, members.clone()));
    let singles = task
        .world
        .objects
        .iter()
        .filter(|o| !grouped.contains(o.name.as_str()))
        .map(|o| (o.name.clone(), false, vec![o.name.clone()]));
    groups.chain(singles).collect()
}

/// For each body, the body it rides on: the one holding what its lowest member with a support
/// outside the body stands on in `world`.
fn carriers(world: &World, bodies: &[Body]) -> Vec<Option<usize>> {
    let body_of: BTreeMap<&str, usize> = bodies
        .iter()
        .enumerate()
        .flat_map(|(i, (_, _, members))| members.iter().map(move |m| (m.as_str(), i)))
        .collect();
    let bottom = |n: &str| world.object(n).map_or(0.0, |o| o.shape.bottom(&o.pose));
    bodies
        .iter()
        .enumerate()
        .map(|(i, (_, _, members))| {
            let mut by_height: Vec<&str> = members.iter().map(String::as_str).collect();
            by_height.sort_by(|a, b| bottom(a).total_cmp(&bottom(b)));
            by_height.iter().find_map(|m| {
                let carrier = *body_of.get(world.support_of(m)?.name.as_str())?;
                (carrier != i).then_some(carrier)
            })
        })
        .collect()
}

/// How many carriers lie under each body; an error names a body that, through its carriers,
/// rides on itself.
fn depths(bodies: &[Body], carriers: &[Option<usize>]) -> Result<Vec<usize>, SceneError> {
    let mut depth: Vec<Option<usize>> = vec![None; bodies.len()];
    for start in 0..bodies.len() {
        // Walk down to a body of known depth (or one on nothing), then number the way back up.
        let mut chain = vec![start];
        while depth[chain[chain.len() - 1]].is_none() {
            let at = chain[chain.len() - 1];
            match carriers[at] {
                None => depth[at] = Some(0),
                Some(c) if chain.contains(&c) => {
                    let (name, group, _) = &bodies[c];
                    let location = if *group {
                        format!("groups.{name}")
                    } else {
                        format!("world.objects ({name})")
                    };
                    return Err(SceneError::invalid(
                        location,
                        "rides, through what it carries, on itself",
                    ));
                }
                Some(c) => chain.push(c),
            }
        }
        let mut d = depth[chain[chain.len() - 1]].unwrap_or(0);
        for &body in chain.iter().rev().skip(1) {
            d += 1;
            depth[body] = Some(d);
        }
    }
    Ok(depth.into_iter().map(|d| d.unwrap_or(0)).collect())
}

fn sample<R: Rng + ?Sized>(rng: &mut R, [lo, hi]: [f64; 2]) -> f64 {
    if hi > lo {
        rng.gen_range(lo..=hi)
    } else {
        lo
    }
}

impl Task {
    /// How randomization moves this task's objects: movers, carriers and ranges.
    pub fn motion(&self) -> Result<Motion, SceneError> {
        Motion::of(self)
    }

    /// The sets of objects that every randomized layout keeps in one fixed relation: the
    /// members of a rigid group, what stands without a range of its own on something that
    /// moves (with it), and everything not moved at all (with `world`). A keyframe grounded on
    /// one member of a set lands where it would grounded on another, so re-grounding between
    /// them is an equivalent grounding, not an error randomization can reveal. Relations that
    /// only the execution creates (an object placed relative to another) are not included:
    /// they depend on the spec. Only sets of two or more names are listed.
    pub fn fixed_relations(&self) -> Result<Vec<FixedRelation>, SceneError> {
        Ok(Motion::of(self)?.fixed_relations(&self.world))
    }

    /// Whether every randomized layout keeps `a` and `b` (object names or `world`) in one
    /// fixed relation (see [`Task::fixed_relations`]).
    pub fn held_together(&self, a: &str, b: &str) -> Result<bool, SceneError> {
        Ok(a == b
            || self
                .fixed_relations()?
                .iter()
                .any(|r| r.members.iter().any(|m| m == a) && r.members.iter().any(|m| m == b)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn carriers_come_before_what_they_carry() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            let motion = Motion::of(&t).unwrap();
            for (i, m) in motion.movers.iter().enumerate() {
                assert!(m.carrier.is_none_or(|c| c < i), "{name}: {}", m.name);
            }
            let mut members: Vec<&str> = motion
                .movers
                .iter()
                .flat_map(|m| m.members.iter().map(String::as_str))
                .collect();
            members.sort();
            let mut objects: Vec<&str> = t.world.names().collect();
            objects.sort();
            assert_eq!(
                members, objects,
                "{name}: every object in exactly one mover"
            );
        }
    }

    #[test]
    fn the_assembly_pipe_rides_on_the_clamp_group() {
        let t = builtin::task("assembly").unwrap().unwrap();
        let motion = Motion::of(&t).unwrap();
        assert_eq!(motion.carrier_of("pipe"), Some("clamp"));
        assert_eq!(motion.carrier_of("block"), Some("shelf_1"));
        assert_eq!(motion.mover_of("clamp_top").unwrap().name, "clamp");
        assert_eq!(motion.carrier_of("rail"), Some("table"));
    }

    #[test]
    fn group_members_and_what_rides_on_a_moved_support_are_moved() {
        let mut t = builtin::task("assembly").unwrap().unwrap();
        let motion = Motion::of(&t).unwrap();
        for name in ["clamp_top", "rail", "pipe", "block", "mat"] {
            assert!(motion.moves(name), "{name}");
        }
        assert!(!motion.moves("table"));
        t.randomize.remove("clamp");
        t.randomize.remove("pipe");
        let motion = Motion::of(&t).unwrap();
        assert!(!motion.moves("clamp_top") && !motion.moves("pipe"));
    }

    #[test]
    fn what_stands_on_a_moved_support_moves_with_it_then_by_its_own_offset() {
        let mut t = builtin::task("pick_place").unwrap().unwrap();
        t.randomize.remove("block_b");
        let motion = Motion::of(&t).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let w = motion.draw(&t.world, &mut rng);
            let relative = |world: &World, name: &str| {
                world.object("shelf_1").unwrap().pose.inverse() * world.object(name).unwrap().pose
            };
            // block_b has no range: it keeps its place on the shelf.
            let d = relative(&w, "block_b").translation.vector
                - relative(&t.world, "block_b").translation.vector;
            assert!(d.norm() < 1e-12);
            // block_a moves on the shelf within its range, along the shelf's axes.
            let d = relative(&w, "block_a").translation.vector
                - relative(&t.world, "block_a").translation.vector;
            let r = t.randomize["block_a"];
            assert!(
                d.x.abs() <= r.x[1] + 1e-12 && d.y.abs() <= r.y[1] + 1e-12,
                "{d:?}"
            );
        }
    }

    #[test]
    fn movers_that_carry_each_other_are_refused_by_name() {
        use crate::{Object, Shape};
        use akl_tsr::pose::pose_from_xyz;
        let mut t = builtin::task("pick_place").unwrap().unwrap();
        // A floating cube, a cube on it, a third on that; the first and third form a group, so
        // the group rides (through its third member) on the middle cube, which rides on it.
        for (name, z) in [("low", 0.5), ("middle", 0.6), ("high", 0.7)] {
            t.world.objects.push(Object {
                name: name.into(),
                shape: Shape::Box {
                    size: [0.1, 0.1, 0.1],
                },
                pose: pose_from_xyz([0.0, 0.6, z]),
                movable: false,
                mass: 0.0,
                friction: 0.5,
            });
        }
        t.groups
            .insert("stack".into(), vec!["low".into(), "high".into()]);
        let e = Motion::of(&t).unwrap_err().to_string();
        assert!(
            e.contains("rides, through what it carries, on itself"),
            "{e}"
        );
        assert!(e.contains("stack") || e.contains("middle"), "{e}");
    }

    #[test]
    fn fixed_relations_name_groups_riders_and_the_world() {
        let t = builtin::task("assembly").unwrap().unwrap();
        let relations = Motion::of(&t).unwrap().fixed_relations(&t.world);
        let sets: Vec<Vec<&str>> = relations
            .iter()
            .map(|r| r.members.iter().map(String::as_str).collect())
            .collect();
        assert!(sets.contains(&vec!["clamp_left", "clamp_right", "clamp_top", "rail"]));
        assert!(sets.contains(&vec!["table", "world"]));
        let mut t = t;
        t.randomize.remove("pipe");
        let relations = Motion::of(&t).unwrap().fixed_relations(&t.world);
        let clamp = relations
            .iter()
            .find(|r| r.members.contains(&"rail".to_string()))
            .unwrap();
        assert!(clamp.members.contains(&"pipe".to_string()), "{clamp:?}");
        assert!(clamp.because.contains("group `clamp`"));
    }
}
