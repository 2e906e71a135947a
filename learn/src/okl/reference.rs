//! Reference objects (thesis §3.2.4): every keyframe is grounded on the key object of the next
//! interaction — the grasped object for a grasp, the object it is put in or on for a release —
//! except a line's pure constraint keyframes over a fixed object (see [`super::pass_over`]).
//!
//! How the key object is found from the object poses:
//! - **grasp** (gripper open → closed at frame g): the object that is carried — among the
//!   objects that move at least [`CARRIED_MOTION`] between g and the next release (or the end),
//!   the one whose pose relative to the end effector changes least, and by at most
//!   [`CARRIED_SLIP`]. If nothing is carried that way (objects not tracked, or the hand did not
//!   move), the object whose centre is nearest the tool centre point at g, movable objects
//!   first when the task's world says which are movable.
//! - **release** (closed → open at frame r): the object that receives the held one (the key
//!   object of the grasp before, else the object nearest the tool centre point) — the object
//!   it ends on or in. Shapes come from the task's world, else from the recording's header
//!   (see [`crate::shapes`]); the rules are tried in turn:
//!   1. *Support rule* (the held object and its candidates have shapes): among the other
//!      objects whose outline seen from above contains the held object's centre and whose
//!      height, widened by [`SUPPORT_GAP`] at both ends, holds the held object's bottom at r
//!      (it rests on their top, or its bottom went into them: a rod in a tube), the one with
//!      the highest top — the rule a task world uses ([`World::support_of`]), with a wider gap
//!      because an object is let go slightly above its support.
//!   2. *Receiver within reach*: among the other objects whose centre is within
//!      [`RECEIVE_REACH`] of the held object's centre both horizontally and vertically, the one
//!      whose centre is nearest in the horizontal plane — below the held centre when the
//!      object was put on it, level with or above it when the object was put into it.
//!   3. *Large support below*: a support larger than the reach (a table, a workbench) has
//!      its centre far from most places on it. Among the other objects whose centre lies below
//!      the held object's centre by at most [`LARGE_SUPPORT_DROP`] and within
//!      [`LARGE_SUPPORT_REACH`] of it horizontally, the one whose centre is lowest (the
//!      nearest horizontally among equals): the furniture the other objects stand on, rather
//!      than a low object beside the release point (a mat, a rail). An object whose shape is
//!      known joins only if its outline contains the held object's centre (and, when the held
//!      object's shape is known too, rule 1 has already judged it and it does not join). How
//!      the rule was chosen is on [`LARGE_SUPPORT_REACH`].
//!
//!   With none found the release is grounded on `world`: the object was let go in free space,
//!   or on furniture the recording does not track.

use crate::demo::Demo;
use std::borrow::Cow;

use akl_scene::{Shape, World};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;

/// Minimum displacement (metres) of an object over a closed-gripper segment to count as carried.
pub(crate) const CARRIED_MOTION: f64 = 0.01;
/// Largest change (metres) of a carried object's position relative to the end effector.
pub(crate) const CARRIED_SLIP: f64 = 0.01;
/// Largest gap (metres) between a held object's bottom and a support's top at a release.
/// Wider than a resting contact: the object is released slightly above its support.
pub(crate) const SUPPORT_GAP: f64 = 0.02;
/// How far (metres, horizontally and vertically, centre to centre) an object may be from a
/// released one and still be taken for what received it when shapes are unknown: 0.25. The
/// built-in tasks put objects down at most 0.13 m (the pipe at the end of the 0.6 m rail)
/// horizontally and 0.12 m vertically from the centre of what receives them (measured by the
/// test `every_builtin_release_is_within_reach_of_its_receiver`); 0.25 m keeps about twice
/// that margin while a release half a metre from everything is grounded on `world`.
pub(crate) const RECEIVE_REACH: f64 = 0.25;
/// How far (metres, horizontally, centre to centre) a large support found by the third rule
/// of [`receiving_object`] may be from the released object: 1.0. It must cover every place on
/// the largest support a recording tracks: the built-in table (1.2 m × 1.4 m) has points
/// 0.92 m from its centre, and a 1 m reach covers every place a Panda (0.855 m reach) can put
/// something on it. Measured by `large_supports_without_shapes_agree_with_the_support_rule`
/// on 2315 release points spread across the tops of the fixed objects of the built-in worlds,
/// every shape forgotten: rule 2 alone names the object the world's support rule names at
/// 13.5 % of them (it finds the table only within 0.25 m of its centre); with rule 3 taking
/// the lowest candidate, 76.1 %, and rule 3 is never wrong — the rest are points within
/// 0.25 m of a neighbouring object, which rule 2 names. Taking the highest candidate instead
/// (a mat or the rail beside the point rather than the table under it) gave 61.9 %, the
/// nearest 71.3 %. Nothing let go 0.3 m above every top is grounded on an object.
pub(crate) const LARGE_SUPPORT_REACH: f64 = 1.0;
/// How far (metres) the centre of a large support found by the third rule of
/// [`receiving_object`] may lie below the released object's centre: 0.17, half the height of
/// the tallest object the built-in tasks carry (a bottle, 0.08) plus half the thickness of the
/// thickest support they put things on (a shelf, 0.07) plus [`SUPPORT_GAP`]. An object let go
/// higher above everything tracked is taken to be let go in free space (the negative control
/// `a_release_far_from_everything_is_grounded_on_the_world` in `learn/tests/fidelity.rs`: a
/// ball let go with its centre 0.2 m above a crate's, 0.8 m away).
pub(crate) const LARGE_SUPPORT_DROP: f64 = 0.17;

/// One object learning can ground on: its poses over the demo and, when known, its shape.
#[derive(Debug, Clone)]
pub struct SceneObject<'a> {
    /// Object name.
    pub name: String,
    /// Pose at every frame (borrowed from the demo), or one pose when the object never moves
    /// (not tracked in the demo).
    pub poses: Cow<'a, [Pose]>,
    /// Shape, from the task's world or the recording's header.
    pub shape: Option<Shape>,
    /// Whether the object can be picked up, from the task's world.
    pub movable: Option<bool>,
}

impl SceneObject<'_> {
    /// Pose at frame `k` (the single pose of an untracked object).
    pub fn pose(&self, k: usize) -> &Pose {
        &self.poses[k.min(self.poses.len() - 1)]
    }

    fn centre(&self, k: usize) -> Vector3<f64> {
        self.pose(k).translation.vector
    }
}

/// The objects of a demo: its tracks, plus the objects of `world` the demo does not track
/// (furniture a driver may not record), fixed at their pose in the world. A tracked object's
/// shape is the world's, else the one the demo's header declares (a mesh whose file was not
/// read counts as unknown).
pub fn scene_objects<'a>(demo: &'a Demo, world: Option<&World>) -> Vec<SceneObject<'a>> {
    let mut out: Vec<SceneObject> = demo
        .objects
        .iter()
        .filter(|t| !t.poses.is_empty())
        .map(|t| {
            let known = world.and_then(|w| w.object(&t.name));
            let declared = demo
                .header
                .shapes
                .get(&t.name)
                .filter(|s| s.validate().is_ok());
            SceneObject {
                name: t.name.clone(),
                poses: Cow::Borrowed(&t.poses),
                shape: known.map(|o| &o.shape).or(declared).cloned(),
                movable: known.map(|o| o.movable),
            }
        })
        .collect();
    if let Some(w) = world {
        for o in &w.objects {
            if !out.iter().any(|s| s.name == o.name) {
                out.push(SceneObject {
                    name: o.name.clone(),
                    poses: Cow::Owned(vec![o.pose]),
                    shape: Some(o.shape.clone()),
                    movable: Some(o.movable),
                });
            }
        }
    }
    out
}

/// The object grasped at frame `grasp` and held until `hold_end` (index into `objects`).
pub(crate) fn grasped_object(
    objects: &[SceneObject],
    ee: &[Pose],
    grasp: usize,
    hold_end: usize,
) -> Option<usize> {
    let relative = |o: &SceneObject, k: usize| (ee[k].inverse() * o.pose(k)).translation.vector;
    let carried = objects
        .iter()
        .enumerate()
        .filter(|(_, o)| (o.centre(hold_end) - o.centre(grasp)).norm() >= CARRIED_MOTION)
        .map(|(i, o)| (i, (relative(o, hold_end) - relative(o, grasp)).norm()))
        .filter(|(_, slip)| *slip <= CARRIED_SLIP)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i);
    carried.or_else(|| nearest_to_tool(objects, ee, grasp))
}

/// The object nearest the tool centre point at frame `k`; movable objects are preferred when
/// the world says which are.
pub(crate) fn nearest_to_tool(objects: &[SceneObject], ee: &[Pose], k: usize) -> Option<usize> {
    let tool = ee[k].translation.vector;
    let nearest = |movable_only: bool| {
        objects
            .iter()
            .enumerate()
            .filter(|(_, o)| !movable_only || o.movable == Some(true))
            .map(|(i, o)| (i, (o.centre(k) - tool).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    nearest(true).or_else(|| nearest(false))
}

/// The object that receives `held` at frame `release`: the one it ends on or in (index into
/// `objects`; see the module docs).
pub(crate) fn receiving_object(
    objects: &[SceneObject],
    held: usize,
    release: usize,
) -> Option<usize> {
    let h = &objects[held];
    let centre = h.centre(release);
    let by_shape = h.shape.as_ref().and_then(|shape| {
        let bottom = shape.bottom(h.pose(release));
        objects
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != held)
            .filter_map(|(i, o)| o.shape.as_ref().map(|s| (i, s, o.pose(release))))
            .filter(|(_, s, pose)| {
                bottom >= s.bottom(pose) - SUPPORT_GAP && bottom <= s.top(pose) + SUPPORT_GAP
            })
            .filter(|(_, s, pose)| {
                let local = pose.inverse_transform_point(&centre.into());
                s.outline_contains(local.x, local.y, 0.0)
            })
            .max_by(|a, b| a.1.top(a.2).total_cmp(&b.1.top(b.2)))
            .map(|(i, _, _)| i)
    });
    by_shape
        .or_else(|| within_reach(objects, held, release))
        .or_else(|| large_support_below(objects, held, release))
}

/// Rule 2 of [`receiving_object`]: the object whose centre is within [`RECEIVE_REACH`] of
/// `held`'s at `release`, horizontally and vertically, and nearest it horizontally.
fn within_reach(objects: &[SceneObject], held: usize, release: usize) -> Option<usize> {
    let centre = objects[held].centre(release);
    objects
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != held)
        .map(|(i, o)| (i, o.centre(release) - centre))
        .filter(|(_, d)| d.xy().norm() <= RECEIVE_REACH && d.z.abs() <= RECEIVE_REACH)
        .min_by(|a, b| a.1.xy().norm().total_cmp(&b.1.xy().norm()))
        .map(|(i, _)| i)
}

/// Rule 3 of [`receiving_object`]: the lowest object whose centre is below `held`'s at
/// `release` by at most [`LARGE_SUPPORT_DROP`] and within [`LARGE_SUPPORT_REACH`] of it
/// horizontally; objects of known shape only when their outline contains `held`'s centre and
/// `held`'s own shape is unknown.
fn large_support_below(objects: &[SceneObject], held: usize, release: usize) -> Option<usize> {
    let h = &objects[held];
    let centre = h.centre(release);
    objects
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != held)
        .filter(|(_, o)| match &o.shape {
            None => true,
            Some(shape) => {
                let local = o.pose(release).inverse_transform_point(&centre.into());
                h.shape.is_none() && shape.outline_contains(local.x, local.y, 0.0)
            }
        })
        .map(|(i, o)| (i, o.centre(release) - centre))
        .filter(|(_, d)| d.z < 0.0 && -d.z <= LARGE_SUPPORT_DROP)
        .filter(|(_, d)| d.xy().norm() <= LARGE_SUPPORT_REACH)
        .min_by(|a, b| (a.1.z.total_cmp(&b.1.z)).then(a.1.xy().norm().total_cmp(&b.1.xy().norm())))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz;

    fn fixed(name: &str, p: [f64; 3], shape: Option<Shape>) -> SceneObject<'static> {
        SceneObject {
            name: name.into(),
            poses: Cow::Owned(vec![pose_from_xyz(p)]),
            shape,
            movable: Some(false),
        }
    }

    #[test]
    fn the_carried_object_is_the_grasped_one() {
        // The hand moves from x = 0 to x = 0.3 carrying `a`; `b` stays.
        let ee: Vec<Pose> = (0..=10)
            .map(|i| pose_from_xyz([i as f64 * 0.03, 0.0, 0.2]))
            .collect();
        let a = SceneObject {
            name: "a".into(),
            poses: ee
                .iter()
                .map(|p| p * pose_from_xyz([0.0, 0.0, -0.02]))
                .collect::<Vec<_>>()
                .into(),
            shape: None,
            movable: None,
        };
        let b = fixed("b", [0.0, 0.01, 0.18], None);
        assert_eq!(grasped_object(&[b.clone(), a.clone()], &ee, 0, 10), Some(1));
        // Without motion, the nearest object wins.
        assert_eq!(grasped_object(&[b, a], &ee, 0, 0), Some(1));
    }

    #[test]
    fn support_by_shape_then_by_position() {
        let box_shape = |x: f64, y: f64, z: f64| Some(Shape::Box { size: [x, y, z] });
        let held = SceneObject {
            name: "block".into(),
            poses: Cow::Owned(vec![pose_from_xyz([0.5, -0.3, 0.18])]),
            shape: box_shape(0.05, 0.05, 0.08),
            movable: Some(true),
        };
        let table = fixed("table", [0.35, 0.0, -0.02], box_shape(1.2, 1.4, 0.04));
        let shelf = fixed("shelf", [0.48, -0.3, 0.07], box_shape(0.22, 0.26, 0.14));
        let objs = vec![table.clone(), held.clone(), shelf.clone()];
        assert_eq!(receiving_object(&objs, 1, 0), Some(2));
        let strip = |mut o: SceneObject<'static>| {
            o.shape = None;
            o
        };
        let objs: Vec<_> = objs.into_iter().map(strip).collect();
        assert_eq!(receiving_object(&objs, 1, 0), Some(2));
    }

    #[test]
    fn a_rod_in_a_tube_is_received_by_the_tube_with_or_without_shapes() {
        let rod = SceneObject {
            name: "rod".into(),
            poses: Cow::Owned(vec![pose_from_xyz([0.5, 0.0, 0.09])]),
            shape: Some(Shape::Cylinder {
                radius: 0.01,
                length: 0.16,
            }),
            movable: Some(true),
        };
        let tube = Shape::Cylinder {
            radius: 0.03,
            length: 0.2,
        };
        let table = Shape::Box {
            size: [1.0, 1.0, 0.04],
        };
        let objs = vec![
            fixed("table", [0.4, 0.1, -0.02], Some(table)),
            rod,
            fixed("tube", [0.5, 0.0, 0.1], Some(tube)),
        ];
        assert_eq!(receiving_object(&objs, 1, 0), Some(2));
        let bare: Vec<_> = objs
            .into_iter()
            .map(|mut o| {
                o.shape = None;
                o
            })
            .collect();
        assert_eq!(receiving_object(&bare, 1, 0), Some(2));
        // Lifted half a metre above everything: nothing receives it.
        let mut lifted = bare.clone();
        lifted[1].poses = Cow::Owned(vec![pose_from_xyz([0.5, 0.0, 0.6])]);
        assert_eq!(receiving_object(&lifted, 1, 0), None);
    }

    /// The measurement behind [`LARGE_SUPPORT_REACH`]: a 5 cm cube let go 5 mm above points
    /// 5 cm apart across the top of every fixed object of every built-in world, where the
    /// world's support rule says that object would hold it (and nothing stands there), is
    /// grounded with every shape forgotten; then the same cube 0.3 m above the highest top.
    #[test]
    fn large_supports_without_shapes_agree_with_the_support_rule() {
        use akl_scene::builtin;
        let cube = Shape::Box {
            size: [0.05, 0.05, 0.05],
        };
        let (mut points, mut rule_2, mut rules_2_3) = (0, 0, 0);
        let (mut rule_3_wrong, mut lifted_grounded) = (0, 0);
        for name in builtin::names() {
            let world = builtin::resolve(name).unwrap().world;
            let highest = world
                .objects
                .iter()
                .map(|o| o.shape.top(&o.pose))
                .fold(f64::MIN, f64::max);
            let mut bare: Vec<SceneObject> = world
                .objects
                .iter()
                .map(|o| fixed(&o.name, o.pose.translation.vector.into(), None))
                .collect();
            bare.push(fixed("cube", [0.0; 3], None));
            let held = bare.len() - 1;
            for support in world.objects.iter().filter(|o| !o.movable) {
                let half = support.shape.half_extents();
                let top = support.shape.top(&support.pose);
                let steps = |h: f64| (-(h / 0.05).floor() as i32)..=((h / 0.05).floor() as i32);
                for i in steps(half.x) {
                    for j in steps(half.y) {
                        let local = [i as f64 * 0.05, j as f64 * 0.05, 0.0];
                        if !support.shape.outline_contains(local[0], local[1], 0.0) {
                            continue;
                        }
                        let at = support.pose * akl_tsr::nalgebra::Point3::from(local);
                        let resting = pose_from_xyz([at.x, at.y, top + 0.025]);
                        let truth = world.support_under(&cube, &resting, "cube");
                        let crowded = world.objects.iter().any(|o| {
                            o.name != support.name
                                && akl_scene::shapes_overlap(&cube, &resting, &o.shape, &o.pose)
                        });
                        if truth.map(|t| t.name.as_str()) != Some(&support.name) || crowded {
                            continue;
                        }
                        points += 1;
                        bare[held].poses =
                            Cow::Owned(vec![pose_from_xyz([at.x, at.y, top + 0.03])]);
                        let named = |found: Option<usize>| {
                            found.map(|k| bare[k].name.as_str()) == Some(&support.name)
                        };
                        let near = within_reach(&bare, held, 0);
                        rule_2 += usize::from(named(near));
                        let found = named(receiving_object(&bare, held, 0));
                        rules_2_3 += usize::from(found);
                        rule_3_wrong += usize::from(near.is_none() && !found);
                        bare[held].poses =
                            Cow::Owned(vec![pose_from_xyz([at.x, at.y, highest + 0.325])]);
                        lifted_grounded += usize::from(receiving_object(&bare, held, 0).is_some());
                    }
                }
            }
        }
        let share = |n: usize| n as f64 / points as f64;
        println!(
            "{points} release points: rule 2 names the support at {:.1} %, rules 2 and 3 at {:.1} % ({rule_3_wrong} wrong by rule 3); lifted 0.3 m, {lifted_grounded} grounded on an object",
            100.0 * share(rule_2),
            100.0 * share(rules_2_3)
        );
        assert!(points > 2000, "{points}");
        assert!(share(rule_2) < 0.2 && share(rules_2_3) > 0.75);
        assert_eq!((rule_3_wrong, lifted_grounded), (0, 0));
    }

    #[test]
    fn every_builtin_release_is_within_reach_of_its_receiver() {
        use akl_scene::{builtin, TeachStep};
        let mut widest: f64 = 0.0;
        for name in builtin::names() {
            let task = builtin::resolve(name).unwrap();
            for step in &task.teaching.steps {
                if let TeachStep::Release { on, place } = step {
                    let offset = place.translation.vector;
                    widest = widest.max(offset.xy().norm()).max(offset.z.abs());
                    assert!(task.world.object(on).is_some());
                }
            }
        }
        assert!(
            widest > 0.1 && 2.0 * widest <= RECEIVE_REACH + 0.01,
            "{widest}"
        );
    }
}
