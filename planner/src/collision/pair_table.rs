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
use super::minima::Minima;
use super::model::{Body, Mover};
use crate::fk::{Drive, Kinematics, Motion};
use crate::geometry::Geometry;
use crate::parry_convert;
use crate::robot::Robot;
use akl_tsr::nalgebra::Vector3;
use sha2::{Digest, Sha256};
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

/// How node values are computed, as part of every table's fingerprint: raise it whenever
/// [`PairTable::node_value`] or the shapes it measures change, so that values a build
/// computed otherwise are never read from a file.
const VALUES_VERSION: u32 = 1;

/// A table's fingerprint: SHA-256 of everything its node values depend on.
pub(super) type Fingerprint = [u8; 32];

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

impl TableJoint {
    /// The index of the node nearest the arm-joint value `v` (an end of the grid for a value
    /// beyond it).
    fn nearest(&self, v: f64) -> usize {
        ((v - self.lo) / self.step)
            .round()
            .clamp(0.0, (self.count - 1) as f64) as usize
    }
}

/// Lower bounds on the distance between the two elements of one self-collision pair, over a
/// grid of the one or two arm joints that move them against each other.
pub(crate) struct PairTable {
    joints: SmallVec<[TableJoint; 2]>,
    /// How much the model grew each element for the other (half its self margin).
    grow: f64,
    cells: Box<[AtomicU32]>,
    /// Whether the values were read from a file when the table was made.
    stored: bool,
    /// Block minima of the values, when all were known when the table was made.
    minima: Option<Minima>,
}

impl std::fmt::Debug for PairTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairTable")
            .field("joints", &self.joints)
            .field("grow", &self.grow)
            .field("nodes", &self.cells.len())
            .field("stored", &self.stored)
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
            stored: false,
            minima: None,
        })
    }

    /// What the table knows of `a` and `b` (each grown by half the self margin) at arm
    /// configuration `q`.
    pub(super) fn lookup(&self, robot: &Robot, a: &Body, b: &Body, q: &[f64]) -> Tabled {
        let mut cell = 0;
        let mut slack = DISTANCE_TOLERANCE;
        for j in &self.joints {
            let v = q[j.index];
            let i = j.nearest(v);
            slack += j.reach * (v - (j.lo + i as f64 * j.step)).abs();
            cell = cell * j.count + i;
        }
        let value = f64::from(self.value_at(robot, a, b, cell));
        if value < 0.0 && -value > slack {
            Tabled::Overlapping
        } else {
            Tabled::Apart(value - slack)
        }
    }

    /// Everything the node values depend on, hashed: the code's version, both elements (link,
    /// shape, pose on the link), how much they are grown, the grid, the ready configuration
    /// and opening the other joints take, both links' poses at three nodes (the robot's
    /// kinematics as far as the values see it) and the values of three nodes. Values stored
    /// under another fingerprint are not this table's.
    pub(super) fn fingerprint(&self, robot: &Robot, a: &Body, b: &Body) -> Fingerprint {
        let mut hash = Sha256::new();
        let mut add = |text: String| hash.update(rounded(&text));
        add(format!(
            "akl {} values {VALUES_VERSION}\n",
            env!("CARGO_PKG_VERSION")
        ));
        for body in [a, b] {
            add(format!(
                "{} {:?} {:?}\n",
                body.link, body.geometry, body.local
            ));
        }
        add(format!("{:?} {:?}\n", self.grow, self.joints));
        add(format!("{:?} {:?}\n", robot.ready(), robot.open_width()));
        let first: SmallVec<[f64; 2]> = self.joints.iter().map(|j| j.lo).collect();
        for stepped in 0..=self.joints.len() {
            let mut node = first.clone();
            if let Some(v) = node.get_mut(stepped) {
                *v += self.joints[stepped].step;
            }
            let poses = robot
                .kinematics()
                .link_poses(&self.configuration(robot, &node), robot.open_width());
            add(format!("{:?} {:?}\n", poses[a.link], poses[b.link]));
        }
        // Three nodes computed now: a change to how values are computed that the version
        // above does not record still changes the fingerprint (to 10 µm, coarser than the
        // last bits another platform's sine may change).
        for cell in [0, self.cells.len() / 2, self.cells.len() - 1] {
            let value = self.node_value(robot, a, b, &self.node_at(cell));
            add(format!("{:.5}\n", (f64::from(value) * 1e5).round() * 1e-5));
        }
        hash.finalize().into()
    }

    /// Number of nodes.
    pub(super) fn len(&self) -> usize {
        self.cells.len()
    }

    /// Computes every node not computed yet, on `threads` threads.
    pub(super) fn fill(&self, robot: &Robot, a: &Body, b: &Body, threads: usize) {
        let share = self.cells.len().div_ceil(threads.max(1)).max(1);
        std::thread::scope(|scope| {
            for start in (0..self.cells.len()).step_by(share) {
                scope.spawn(move || {
                    for cell in start..(start + share).min(self.cells.len()) {
                        self.value_at(robot, a, b, cell);
                    }
                });
            }
        });
    }

    /// Every node's value, `None` while some are not computed.
    pub(super) fn values(&self) -> Option<Vec<f32>> {
        self.cells
            .iter()
            .map(|c| {
                let bits = c.load(Ordering::Relaxed);
                (bits != UNKNOWN).then(|| f32::from_bits(bits))
            })
            .collect()
    }

    /// Takes `values` (one per node, in node order, as [`PairTable::values`] gives them) as
    /// the nodes' values, read from a file; nothing is taken if their number is not the
    /// table's or one is not a number.
    pub(super) fn take_values(&mut self, values: &[f32]) {
        if values.len() != self.cells.len() || values.iter().any(|v| v.is_nan()) {
            return;
        }
        for (cell, v) in self.cells.iter().zip(values) {
            cell.store(v.to_bits(), Ordering::Relaxed);
        }
        self.stored = true;
        let columns = self.joints.get(1).map_or(1, |j| j.count);
        self.minima = Some(Minima::new(self.joints[0].count, columns, values));
    }

    /// Whether the two elements (each grown by half the self margin) stay more than `least`
    /// apart wherever the arm goes within `share`·|`step`| (per arm joint) of `q` within the
    /// joint limits: the stretch of an edge proof, bounded at once where the bound at one
    /// configuration would shrink by the stretch's whole motion. Known only for tables whose
    /// values were all known when they were made (false otherwise, and where a node in the
    /// box holds no distance).
    ///
    /// Every configuration in the box has its nearest node among the nodes of the box's
    /// cells, at most half a step away along each table joint; the least of those nodes'
    /// values, less what half a step can move the moving element, bounds the box.
    pub(super) fn clear_over(
        &self,
        robot: &Robot,
        q: &[f64],
        (step, share): (&[f64], f64),
        least: f64,
    ) -> bool {
        let Some(minima) = &self.minima else {
            return false;
        };
        let limits = robot.joint_limits();
        let mut ranges = [(0, 0); 2];
        let mut slack = DISTANCE_TOLERANCE;
        for (range, j) in ranges.iter_mut().zip(&self.joints) {
            let [lo, hi] = limits[j.index];
            let reach = share * step[j.index].abs();
            // In order: `nearest` is monotonic and clamps to the grid, whose ends are the limits.
            *range = (
                j.nearest((q[j.index] - reach).max(lo)),
                j.nearest((q[j.index] + reach).min(hi)),
            );
            slack += j.reach * 0.5 * j.step;
        }
        let value = f64::from(minima.least(ranges[0], ranges[1]));
        value > 0.0 && value - slack > least
    }

    /// Whether the values were read from a file when the table was made.
    pub(super) fn stored(&self) -> bool {
        self.stored
    }

    /// Node `cell`'s value, computed and kept the first time it is asked for.
    fn value_at(&self, robot: &Robot, a: &Body, b: &Body, cell: usize) -> f32 {
        let bits = self.cells[cell].load(Ordering::Relaxed);
        if bits != UNKNOWN {
            return f32::from_bits(bits);
        }
        let v = self.node_value(robot, a, b, &self.node_at(cell));
        self.cells[cell].store(v.to_bits(), Ordering::Relaxed);
        v
    }

    /// The table joints' values at node `cell` (the first joint varies slowest).
    fn node_at(&self, cell: usize) -> SmallVec<[f64; 2]> {
        let mut node: SmallVec<[f64; 2]> = SmallVec::from_elem(0.0, self.joints.len());
        let mut rest = cell;
        for (k, j) in self.joints.iter().enumerate().rev() {
            node[k] = j.lo + (rest % j.count) as f64 * j.step;
            rest /= j.count;
        }
        node
    }

    /// The arm configuration of a node: the ready configuration with the table's joints at
    /// `values`.
    fn configuration(&self, robot: &Robot, values: &[f64]) -> Vec<f64> {
        let mut q = robot.ready().to_vec();
        for (j, v) in self.joints.iter().zip(values) {
            q[j.index] = *v;
        }
        q
    }

    /// The value of a node, with the arm at its ready configuration and the table's joints at
    /// `values`: the distance (a lower bound), or where the two overlap, minus how deep a point
    /// lies in both (a lower bound too); rounded towards zero to single precision.
    fn node_value(&self, robot: &Robot, a: &Body, b: &Body, values: &[f64]) -> f32 {
        let q = self.configuration(robot, values);
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

/// `text` with every number in it rounded to nine decimals (zero without a sign): what a
/// fingerprint hashes, so that the last bits another platform's sine and cosine may change
/// in a pose do not change it.
fn rounded(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut token = String::new();
    let flush = |token: &mut String, out: &mut String| {
        match token.parse::<f64>() {
            Ok(v) => {
                let r = (v * 1e9).round() / 1e9;
                out.push_str(&format!("{:.9}", if r == 0.0 { 0.0 } else { r }));
            }
            Err(_) => out.push_str(token),
        }
        token.clear();
    };
    for c in text.chars() {
        if c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E') {
            token.push(c);
        } else {
            flush(&mut token, &mut out);
            out.push(c);
        }
    }
    flush(&mut token, &mut out);
    out
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

    /// A new table, nothing stored in it, for the first of `model`'s pairs that has one, its
    /// elements grown by `grow`: made as the model makes its own.
    fn new_table_for_first_pair(robot: &Robot, model: &RobotCollision, grow: f64) -> PairTable {
        let (p, &(i, j)) = model
            .self_pairs
            .iter()
            .enumerate()
            .find(|(p, _)| model.tables[*p].is_some())
            .unwrap();
        let s = model.self_shared[p];
        let chain =
            |k: usize| super::super::model::chain_to(robot.kinematics(), model.bodies[k].link);
        let (a, b) = (chain(i), chain(j));
        let beyond = [&a[s..], &b[s..]];
        PairTable::for_pair(robot, &model.bodies[i], &model.bodies[j], beyond, grow).unwrap()
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

    /// A node's value is the same whichever configuration first asked for it (tables filled
    /// as checks reach them: the model without margins has none stored).
    #[test]
    fn a_node_does_not_depend_on_who_filled_it() {
        let robot = Robot::panda().unwrap();
        let [_, model] = with_and_without_margins(&robot);
        let (t, a, b) = tabled(&model)[0];
        let fresh = new_table_for_first_pair(&robot, &model, t.grow);
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

    /// The built-in Panda's tables are read from robots/panda/self_tables.bin, and what was
    /// read is what the nodes compute (300 random nodes per table, to a micrometre: the
    /// platform's sine and cosine may differ in their last bits).
    #[test]
    fn the_built_in_tables_are_stored_and_current() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let summary = model.table_summary();
        assert!(summary.tables > 0);
        assert_eq!(
            summary.stored, summary.tables,
            "robots/panda/self_tables.bin does not fit the built-in Panda's collision model: \
             write it again with `cargo run --release -- robot tables -o robots/panda/self_tables.bin`"
        );
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for (t, a, b) in tabled(&model) {
            let values = t.values().expect("stored tables know every node");
            for _ in 0..300 {
                let cell = rng.gen_range(0..t.len());
                let computed = t.node_value(&robot, a, b, &t.node_at(cell));
                assert!(
                    (f64::from(computed) - f64::from(values[cell])).abs() <= 1e-6,
                    "node {cell}: stored {}, computed {computed}",
                    values[cell]
                );
            }
        }
    }

    /// Stored values are taken only by tables with their fingerprint: a model with other
    /// margins, or a robot with another ready configuration (which the nodes' other joints
    /// take), fills its tables itself.
    #[test]
    fn other_margins_or_another_robot_ignore_the_stored_tables() {
        let robot = Robot::panda().unwrap();
        let [with, bare] = with_and_without_margins(&robot);
        assert_eq!(with.table_summary().stored, with.table_summary().tables);
        assert_eq!(bare.table_summary().stored, 0);
        let toml = crate::robot::PANDA_TOML.replace(
            "ready = [0.0, -0.7853981633974483,",
            "ready = [0.1, -0.7853981633974483,",
        );
        assert_ne!(toml, crate::robot::PANDA_TOML);
        let moved = Robot::panda_with(&toml).unwrap();
        let model = RobotCollision::new(&moved);
        assert_eq!(model.table_summary().stored, 0);
        assert!(tabled(&model).iter().all(|(t, _, _)| t.values().is_none()));
    }

    /// Filling a table computes every node once, whatever the number of threads, to the
    /// values a lookup would compute.
    #[test]
    fn filled_tables_hold_every_node() {
        let robot = Robot::panda().unwrap();
        let bare = Margins {
            arm: 0.0,
            hand: 0.0,
            held: 0.0,
            self_: 0.0,
        };
        let model = RobotCollision::with_margins(&robot, bare);
        let stored = model.fill_tables(&robot, 3);
        assert_eq!(stored.len(), model.table_summary().tables);
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for (t, a, b) in tabled(&model) {
            let values = t.values().expect("filled");
            assert_eq!(stored.get(&t.fingerprint(&robot, a, b)), Some(&values[..]));
            for _ in 0..50 {
                let cell = rng.gen_range(0..t.len());
                let computed = t.node_value(&robot, a, b, &t.node_at(cell));
                assert_eq!(computed.to_bits(), values[cell].to_bits());
            }
        }
    }

    /// A stretch a stored table clears keeps its pair apart by the asked distance all
    /// through it (its corners in the table's joints and random configurations in it, the
    /// distance measured by parry), it clears many stretches (it is worth asking), and a
    /// table filled as checks go has no block minima and clears none.
    #[test]
    fn a_stretch_the_table_clears_is_clear_throughout() {
        let robot = Robot::panda().unwrap();
        let [with, bare] = with_and_without_margins(&robot);
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for ((t, a, b), (unstored, _, _)) in tabled(&with).into_iter().zip(tabled(&bare)) {
            let (mut asked, mut cleared) = (0, 0);
            for _ in 0..400 {
                let q = random_q(&robot, &mut rng);
                let half: Vec<f64> = q.iter().map(|_| rng.gen_range(0.0..0.3)).collect();
                let least = rng.gen_range(-0.005..0.01);
                asked += 1;
                assert!(!unstored.clear_over(&robot, &q, (&half, 1.0), least));
                if !t.clear_over(&robot, &q, (&half, 1.0), least) {
                    continue;
                }
                cleared += 1;
                for k in 0..24 {
                    let mut x: Vec<f64> = q
                        .iter()
                        .zip(&half)
                        .map(|(v, h)| v + rng.gen_range(-h..=*h))
                        .collect();
                    if k < 4 {
                        for (n, j) in t.joints.iter().enumerate() {
                            let side = if (k >> n) & 1 == 0 { -1.0 } else { 1.0 };
                            x[j.index] = q[j.index] + side * half[j.index];
                        }
                    }
                    for (v, [lo, hi]) in x.iter_mut().zip(robot.joint_limits()) {
                        *v = v.clamp(*lo, *hi);
                    }
                    let poses = robot.kinematics().link_poses(&x, robot.open_width());
                    let (pa, pb) = (placed(a, &poses[a.link]), placed(b, &poses[b.link]));
                    let apart = !parry_convert::intersects(
                        &a.self_shape,
                        &pa.pose,
                        &b.self_shape,
                        &pb.pose,
                    );
                    let d =
                        parry_convert::distance(&a.self_shape, &pa.pose, &b.self_shape, &pb.pose)
                            .filter(|_| apart)
                            .unwrap_or(-f64::INFINITY);
                    assert!(
                        d > least,
                        "cleared about {q:?} (±{half:?}) above {least}, but {d} at {x:?}"
                    );
                }
            }
            assert!(
                cleared * 4 >= asked,
                "{cleared} of {asked} stretches cleared"
            );
        }
    }

    /// Numbers are rounded to nine decimals wherever they stand in the text; words and
    /// punctuation stay.
    #[test]
    fn fingerprints_hash_numbers_rounded() {
        assert_eq!(
            rounded("Box { size: [0.1000000000000001, -2e-12, 3] } link5"),
            "Box { size: [0.100000000, 0.000000000, 3.000000000] } link5.000000000"
        );
        assert_eq!(rounded("q7 0.30000000000000004"), rounded("q7 0.3"));
        assert_ne!(rounded("0.3000001"), rounded("0.3"));
    }

    /// Values of another number of nodes, or holding a NaN (a node not computed), are not
    /// taken: the table stays unstored, without block minima, and fills itself.
    #[test]
    fn values_that_do_not_fit_are_not_taken() {
        let robot = Robot::panda().unwrap();
        let [_, model] = with_and_without_margins(&robot);
        let make = || new_table_for_first_pair(&robot, &model, 0.0);
        let n = make().len();
        let mut nan = vec![0.01; n];
        nan[n / 2] = f32::NAN;
        for values in [vec![0.01; n - 1], nan] {
            let mut table = make();
            table.take_values(&values);
            assert!(!table.stored() && table.minima.is_none() && table.values().is_none());
        }
        let mut table = make();
        table.take_values(&vec![0.01; n]);
        assert!(table.stored() && table.minima.is_some());
    }
}
