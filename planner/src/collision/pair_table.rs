//! Tabulated distances for link pairs that only one or two arm joints move against each other.
//!
//! Near the wrist the balls that cull exact tests always overlap: of 1,000 random Panda
//! configurations, link 5 against the hand reaches parry's GJK in 898 and link 5 against
//! link 7 in 954, more than every other pair together. Yet their relative pose depends on
//! joints 6 and 7 only. A [`PairTable`] holds, at each node of a grid over those joints, a
//! lower bound on the distance between the two elements (each grown by half the self margin),
//! computed the first time a check needs that node. At any configuration the distance is at
//! least the nearest node's value less how far the joint offsets can move a point of the
//! moving element (`reach`·|Δ| per joint), so a positive bound settles the pair without
//! parry, and in an edge proof credits that clearance. A node's value depends on the node
//! alone (it is computed at the robot's ready configuration with the table's joints set), so
//! what a check concludes never depends on which checks ran before it.

use super::checker::DISTANCE_TOLERANCE;
use super::cull::placed;
use super::model::{Body, Mover};
use crate::fk::{Drive, Kinematics, Motion};
use crate::geometry::Geometry;
use crate::parry_convert;
use crate::robot::Robot;
use akl_tsr::nalgebra::Vector3;
use smallvec::SmallVec;
use std::sync::atomic::{AtomicU32, Ordering};

/// Largest amount (metres) one table joint's offset from the nearest node may lower the bound:
/// each joint's grid step is `2·CELL_SLACK / reach`. Chosen by measurement (BENCHMARKS.md,
/// "Wrist tables").
const CELL_SLACK: f64 = 0.002;

/// Most nodes in one table (4 bytes each); coarser steps beyond it.
const MAX_NODES: usize = 1 << 18;

/// The stored pattern of a node not computed yet (a NaN, which no distance is).
const UNKNOWN: u32 = u32::MAX;

/// One joint a table runs over.
#[derive(Debug, Clone, Copy)]
struct TableJoint {
    /// Index in the arm configuration.
    index: usize,
    /// The grid's first node and its spacing, in arm-joint values.
    lo: f64,
    step: f64,
    count: usize,
    /// How far (metres) a point of the moving element can move per unit of the arm value.
    reach: f64,
}

/// Lower bounds on the distance between the two elements of one self-collision pair, over a
/// grid of the one or two arm joints that move them against each other.
pub(crate) struct PairTable {
    joints: SmallVec<[TableJoint; 2]>,
    /// How much the model grew each element for the other (half its self margin).
    grow: f64,
    cells: Box<[AtomicU32]>,
}

impl std::fmt::Debug for PairTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairTable")
            .field("joints", &self.joints)
            .field("grow", &self.grow)
            .field("nodes", &self.cells.len())
            .finish()
    }
}

/// Whether the gripper's opening moves `link` (a finger, or anything beyond one).
fn moves_with_gripper(kin: &Kinematics, link: usize) -> bool {
    let links = kin.links();
    let mut at = Some(link);
    while let Some(i) = at {
        if let Motion::Revolute { drive, .. } | Motion::Prismatic { drive, .. } = links[i].motion {
            if matches!(drive, Drive::Width { .. }) {
                return true;
            }
        }
        at = links[i].parent;
    }
    false
}

/// Distance from `p` to the line through `origin` along the unit vector `axis`.
fn to_axis(p: &Vector3<f64>, origin: &Vector3<f64>, axis: &Vector3<f64>) -> f64 {
    (p - origin).cross(axis).norm()
}

impl PairTable {
    /// A table for elements `a` and `b` of `robot`, each grown by `grow` for the other, whose
    /// chains of arm joints (the model's `chains`) go on past their shared joints with `beyond`: if
    /// one or two arm joints, each turning and used once, are all that move one element
    /// against the other (and neither moves with the gripper).
    pub(super) fn for_pair(
        robot: &Robot,
        a: &Body,
        b: &Body,
        beyond: [&[Mover]; 2],
        grow: f64,
    ) -> Option<PairTable> {
        let kin = robot.kinematics();
        if moves_with_gripper(kin, a.link) || moves_with_gripper(kin, b.link) {
            return None;
        }
        let (moving, path) = match beyond {
            [[], []] => return None,
            [[], path] => (b, path),
            [path, []] => (a, path),
            _ => return None,
        };
        if path.len() > 2 || (path.len() == 2 && path[0].index == path[1].index) {
            return None;
        }
        // Reaches from the ready configuration: the moving element's ball and every axis on
        // the path keep their places relative to the joints beyond them.
        let poses = kin.link_poses(robot.ready(), robot.open_width());
        let at = placed(moving, &poses[moving.link]);
        let centre = 0.5 * (at.a + at.b);
        let radius = moving.half_segment + moving.self_radius;
        let axes = path
            .iter()
            .map(|m| {
                let turned = poses[m.link];
                Some((turned.translation.vector, turned.rotation * m.axis?))
            })
            .collect::<Option<SmallVec<[_; 2]>>>()?;
        let last = axes[path.len() - 1];
        let mut reaches = vec![0.0; path.len()];
        reaches[path.len() - 1] = to_axis(&centre, &last.0, &last.1) + radius;
        if path.len() == 2 {
            let first = axes[0];
            reaches[0] = to_axis(&last.0, &first.0, &first.1) + (centre - last.0).norm() + radius;
        }
        let limits = robot.joint_limits();
        let mut joints: SmallVec<[TableJoint; 2]> = path
            .iter()
            .zip(&reaches)
            .map(|(p, &reach)| {
                let [lo, hi] = limits[p.index];
                let reach = reach * p.scale.abs();
                let count = (((hi - lo) * reach / (2.0 * CELL_SLACK)).ceil() as usize).max(1) + 1;
                TableJoint {
                    index: p.index,
                    lo,
                    step: (hi - lo) / (count - 1) as f64,
                    count,
                    reach,
                }
            })
            .collect();
        while joints.iter().map(|j| j.count).product::<usize>() > MAX_NODES {
            for j in &mut joints {
                let span = j.step * (j.count - 1) as f64;
                j.count = j.count.div_ceil(2).max(2);
                j.step = span / (j.count - 1) as f64;
            }
        }
        let nodes = joints.iter().map(|j| j.count).product();
        Some(PairTable {
            joints,
            grow,
            cells: (0..nodes).map(|_| AtomicU32::new(UNKNOWN)).collect(),
        })
    }

    /// What the table knows of `a` and `b` (each grown by half the self margin) at arm
    /// configuration `q`.
    pub(super) fn lookup(&self, robot: &Robot, a: &Body, b: &Body, q: &[f64]) -> Tabled {
        let mut cell = 0;
        let mut slack = DISTANCE_TOLERANCE;
        let mut node = [0.0; 2];
        for (k, j) in self.joints.iter().enumerate() {
            let v = q[j.index];
            let i = ((v - j.lo) / j.step)
                .round()
                .clamp(0.0, (j.count - 1) as f64) as usize;
            node[k] = j.lo + i as f64 * j.step;
            slack += j.reach * (v - node[k]).abs();
            cell = cell * j.count + i;
        }
        let bits = self.cells[cell].load(Ordering::Relaxed);
        let value = if bits == UNKNOWN {
            let v = self.node_value(robot, a, b, &node[..self.joints.len()]);
            self.cells[cell].store(v.to_bits(), Ordering::Relaxed);
            v
        } else {
            f32::from_bits(bits)
        };
        let value = f64::from(value);
        if value < 0.0 && -value > slack {
            Tabled::Overlapping
        } else {
            Tabled::Apart(value - slack)
        }
    }

    /// The value of a node, with the arm at its ready configuration and the table's joints at
    /// `values`: the distance (a lower bound), or where the two overlap, minus how deep a point
    /// lies in both (a lower bound too); rounded towards zero to single precision.
    fn node_value(&self, robot: &Robot, a: &Body, b: &Body, values: &[f64]) -> f32 {
        let mut q = robot.ready().to_vec();
        for (j, v) in self.joints.iter().zip(values) {
            q[j.index] = *v;
        }
        let poses = robot.kinematics().link_poses(&q, robot.open_width());
        let (pa, pb) = (placed(a, &poses[a.link]), placed(b, &poses[b.link]));
        let d = parry_convert::distance(&a.self_shape, &pa.pose, &b.self_shape, &pb.pose)
            .unwrap_or(0.0);
        let value = if d > 0.0 {
            d
        } else {
            parry_convert::overlap_point(&a.self_shape, &pa.pose, &b.self_shape, &pb.pose)
                .and_then(|w| {
                    let depth = depth_in(a, &pa.pose, self.grow, &w)?
                        .min(depth_in(b, &pb.pose, self.grow, &w)?);
                    (depth > 0.0).then_some(-depth)
                })
                .unwrap_or(0.0)
        };
        toward_zero(value)
    }
}

/// What a table tells of a pair at a configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Tabled {
    /// A lower bound on the distance (nothing known when it is 0 or less).
    Apart(f64),
    /// A point lies inside both elements: they collide.
    Overlapping,
}

/// `v` in single precision, rounded towards zero.
fn toward_zero(v: f64) -> f32 {
    let r = v as f32;
    if f64::from(r).abs() > v.abs() {
        if r > 0.0 {
            r.next_down()
        } else {
            r.next_up()
        }
    } else {
        r
    }
}

/// A lower bound on how deep the world point `w` lies in element `body` at `pose`, grown by
/// `grow` (negative: outside, or not known to be inside); `None` for shapes without one here
/// (cylinders). Exact inside a hull's faces (the nearest face plane) and for boxes, capsules
/// and spheres; outside a hull's faces, the rounding less the distance to the nearest vertex.
fn depth_in(body: &Body, pose: &akl_tsr::Pose, grow: f64, w: &Vector3<f64>) -> Option<f64> {
    let p = pose.inverse_transform_point(&(*w).into()).coords;
    Some(match &body.geometry {
        Geometry::RoundHull(hull) => {
            let r = hull.border + grow;
            let mut inside = f64::INFINITY;
            for t in &hull.triangles {
                let [x, y, z] = t.map(|i| hull.vertices[i as usize].coords);
                let n = (y - x).cross(&(z - x));
                let norm = n.norm();
                if norm > 0.0 {
                    inside = inside.min(-(p - x).dot(&n) / norm);
                }
            }
            if inside >= 0.0 {
                r + inside
            } else {
                let nearest = hull
                    .vertices
                    .iter()
                    .map(|v| (p - v.coords).norm())
                    .fold(f64::INFINITY, f64::min);
                r - nearest
            }
        }
        Geometry::Box { size } => {
            let e = Vector3::new(0.5 * size[0], 0.5 * size[1], 0.5 * size[2]);
            let beyond = p.abs() - e;
            if beyond.max() <= 0.0 {
                grow - beyond.max()
            } else {
                grow - beyond.sup(&Vector3::zeros()).norm()
            }
        }
        Geometry::Capsule { radius, length } => {
            let z = p.z.clamp(-0.5 * length, 0.5 * length);
            radius + grow - (p - Vector3::new(0.0, 0.0, z)).norm()
        }
        Geometry::Sphere { radius } => radius + grow - p.norm(),
        Geometry::Cylinder { .. } => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{Margins, RobotCollision};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_q(robot: &Robot, rng: &mut ChaCha8Rng) -> Vec<f64> {
        robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..*hi))
            .collect()
    }

    /// The tabled pairs of the built-in Panda, as (table, element, element, names).
    fn tabled(model: &RobotCollision) -> Vec<(&PairTable, &Body, &Body)> {
        model
            .self_pairs
            .iter()
            .zip(model.tables.iter())
            .filter_map(|(&(i, j), t)| Some((t.as_ref()?, &model.bodies[i], &model.bodies[j])))
            .collect()
    }

    /// The robot's model with its margins, and one whose elements are not grown at all (as
    /// `akl robot check --margin 0` builds).
    fn with_and_without_margins(robot: &Robot) -> [RobotCollision; 2] {
        let bare = Margins {
            arm: 0.0,
            hand: 0.0,
            held: 0.0,
            self_: 0.0,
        };
        [
            RobotCollision::new(robot),
            RobotCollision::with_margins(robot, bare),
        ]
    }

    #[test]
    fn the_panda_tables_its_wrist_pairs_over_joints_6_and_7_only() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let links = robot.links();
        let mut names: Vec<String> = tabled(&model)
            .iter()
            .map(|(t, a, b)| {
                let joints: Vec<usize> = t.joints.iter().map(|j| j.index).collect();
                assert_eq!(joints, [5, 6]);
                format!("{}|{}", links[a.link].name, links[b.link].name)
            })
            .collect();
        names.dedup();
        assert_eq!(names, ["fer_link5|fer_link7", "fer_link5|fer_hand"]);
        // Pairs with a finger move with the gripper too: no table.
        for (&(i, j), t) in model.self_pairs.iter().zip(model.tables.iter()) {
            let pair = [
                &links[model.bodies[i].link].name,
                &links[model.bodies[j].link].name,
            ];
            if pair.iter().any(|n| n.contains("finger")) {
                assert!(t.is_none(), "{pair:?}");
            }
        }
    }

    /// The bound never exceeds parry's distance, anywhere in a cell (random configurations,
    /// and the middles between nodes, where the offset is largest), a pair it calls
    /// overlapping does overlap, and it settles most configurations of the forearm against
    /// link 7 and the hand either way; with the robot's margins and with a model whose
    /// elements are not grown for each other (as `akl robot check --margin 0` builds).
    #[test]
    fn the_table_is_never_wrong_and_settles_most_wrists() {
        let robot = Robot::panda().unwrap();
        for model in with_and_without_margins(&robot) {
            never_wrong_on(&robot, &model);
        }
    }

    /// Where a node's elements overlap, the depth it stores (a point deep in both) is never
    /// more than parry's penetration depth there, with the robot's margins and without any.
    #[test]
    fn an_overlap_is_never_deeper_than_the_penetration() {
        let robot = Robot::panda().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for model in with_and_without_margins(&robot) {
            let mut overlaps = 0;
            for (t, a, b) in tabled(&model) {
                for _ in 0..2000 {
                    let values: Vec<f64> = t
                        .joints
                        .iter()
                        .map(|j| j.lo + rng.gen_range(0..j.count) as f64 * j.step)
                        .collect();
                    let value = f64::from(t.node_value(&robot, a, b, &values));
                    if value >= 0.0 {
                        continue;
                    }
                    overlaps += 1;
                    let mut q = robot.ready().to_vec();
                    for (j, v) in t.joints.iter().zip(&values) {
                        q[j.index] = *v;
                    }
                    let poses = robot.kinematics().link_poses(&q, robot.open_width());
                    let (pa, pb) = (placed(a, &poses[a.link]), placed(b, &poses[b.link]));
                    let depth = parry_convert::penetration(
                        &a.self_shape,
                        &pa.pose,
                        &b.self_shape,
                        &pb.pose,
                    )
                    .unwrap();
                    assert!(
                        -value <= depth + 1e-9,
                        "{} deep, parry {depth} at {q:?}",
                        -value
                    );
                }
            }
            assert!(overlaps > 100, "only {overlaps} overlapping nodes");
        }
    }

    fn never_wrong_on(robot: &Robot, model: &RobotCollision) {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for (t, a, b) in tabled(model) {
            let (mut free, mut apart, mut hit, mut overlapping) = (0, 0, 0, 0);
            for k in 0..3000 {
                let mut q = random_q(robot, &mut rng);
                if k % 2 == 1 {
                    for j in &t.joints {
                        let i = ((q[j.index] - j.lo) / j.step).floor();
                        q[j.index] = j.lo + (i + 0.5) * j.step * (1.0 - 1e-12);
                    }
                }
                let poses = robot.kinematics().link_poses(&q, robot.open_width());
                let (pa, pb) = (placed(a, &poses[a.link]), placed(b, &poses[b.link]));
                let d = parry_convert::distance(&a.self_shape, &pa.pose, &b.self_shape, &pb.pose)
                    .unwrap();
                let meet =
                    parry_convert::intersects(&a.self_shape, &pa.pose, &b.self_shape, &pb.pose);
                match t.lookup(robot, a, b, &q) {
                    Tabled::Apart(bound) => {
                        assert!(bound <= d, "bound {bound} above the distance {d} at {q:?}");
                        apart += usize::from(bound > 0.0);
                    }
                    Tabled::Overlapping => {
                        assert!(meet, "called overlapping, parry finds {d} m apart at {q:?}");
                        overlapping += 1;
                    }
                }
                if meet {
                    hit += 1;
                } else {
                    free += 1;
                }
            }
            assert!(apart * 10 >= free * 8, "{apart} of {free} free settled");
            assert!(
                overlapping * 10 >= hit * 3,
                "{overlapping} of {hit} collisions settled"
            );
        }
    }

    /// Depths of points in a hull and a box: exact inside, a lower bound outside a hull's
    /// faces, and negative outside the grown shape.
    #[test]
    fn depths_of_points_bound_the_true_depth() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let pose = akl_tsr::Pose::identity();
        for body in &model.bodies {
            for _ in 0..300 {
                let w = Vector3::new(
                    rng.gen_range(-0.15..0.15),
                    rng.gen_range(-0.15..0.15),
                    rng.gen_range(-0.15..0.15),
                );
                let Some(depth) = depth_in(body, &pose, 0.005, &w) else {
                    continue;
                };
                let (shape, _) = parry_convert::robot_shape(&body.geometry, 0.005);
                let ball = parry3d_f64::shape::SharedShape::ball(1e-9);
                let at = akl_tsr::pose::pose_from_xyz([w.x, w.y, w.z]);
                let inside = parry_convert::intersects(&shape, &pose, &ball, &at);
                if depth > 1e-9 {
                    assert!(inside, "{w:?} called {depth} deep, parry finds it outside");
                }
                if !inside {
                    assert!(depth <= 1e-9, "{w:?} outside, called {depth} deep");
                }
            }
        }
    }

    /// A node's value is the same whichever configuration first asked for it.
    #[test]
    fn a_node_does_not_depend_on_who_filled_it() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let (t, a, b) = tabled(&model)[0];
        let (p, &(i, j)) = model
            .self_pairs
            .iter()
            .enumerate()
            .find(|(p, _)| model.tables[*p].is_some())
            .unwrap();
        let s = model.self_shared[p];
        let beyond = [&model.chains[i][s..], &model.chains[j][s..]];
        let fresh = PairTable::for_pair(&robot, a, b, beyond, t.grow).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..50 {
            let q = random_q(&robot, &mut rng);
            let mut other = random_q(&robot, &mut rng);
            for j in &t.joints {
                other[j.index] = q[j.index];
            }
            let first = t.lookup(&robot, a, b, &other);
            assert_eq!(first, t.lookup(&robot, a, b, &q));
            assert_eq!(fresh.lookup(&robot, a, b, &q), first);
        }
    }
}
