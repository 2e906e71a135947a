//! Collision checking of the arm, the hand and a held object against the world and the arm
//! itself, with parry3d shapes and cheap bounding-box culling before each exact test.
//!
//! Margins (from `robot.toml`): arm links are grown by `arm_margin`, hand links by
//! `hand_margin` and a held object by `held_margin` before being tested against the exact
//! world objects; two links are each grown by half of `self_margin` before being tested
//! against each other. Link pairs in `allowed_pairs` are never tested, nor `mount_links`
//! against the object under the robot base.

use crate::fk::Kinematics;
use crate::geometry::Geometry;
use crate::parry_convert;
use crate::robot::Robot;
use akl_scene::{Shape, World};
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use parry3d::shape::SharedShape;
use std::fmt;

/// Most links a robot may have (link poses live on the stack during a check).
pub const MAX_LINKS: usize = 32;

/// Most collision elements a robot may have (they are placed on the stack during a check).
pub const MAX_BODIES: usize = 40;

/// Which margin a link's shapes get.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// Arm links (`arm_margin`).
    Arm,
    /// Hand and finger links (`hand_margin`).
    Hand,
}

/// One collision element of the robot, prepared for checking.
#[derive(Debug, Clone)]
struct Body {
    link: usize,
    group: Group,
    /// Pose of the parry shape in the link frame.
    local: Pose,
    /// Grown by the group's margin, for tests against the world and a held object.
    world_shape: SharedShape,
    /// Grown by half the self margin, for tests between links.
    self_shape: SharedShape,
    /// Half the capsule's segment (0 for other shapes) and the radius of a ball around the
    /// segment that holds the grown shape.
    half_segment: f64,
    world_radius: f64,
    self_radius: f64,
}

/// The robot's collision model: its shapes, the link pairs to test and the displacement
/// bounds used to space checks along edges.
#[derive(Debug, Clone)]
pub struct RobotCollision {
    bodies: Vec<Body>,
    self_pairs: Vec<(usize, usize)>,
    mount_links: Vec<usize>,
    margins: Margins,
    reach: Reach,
    tcp: usize,
}

/// The clearances kept (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Margins {
    /// Arm links against the world.
    pub arm: f64,
    /// Hand links against the world.
    pub hand: f64,
    /// A held object against the world and the arm.
    pub held: f64,
    /// Between links.
    pub self_: f64,
}

/// For each arm joint, how far from its axis a point of each group can be (metres): moving
/// joint j by Δ moves such a point by at most `radius·|Δ|` (or `|Δ|` for a prismatic joint).
#[derive(Debug, Clone, PartialEq)]
pub struct Reach {
    /// Arm-link shapes.
    pub arm: Vec<f64>,
    /// Hand-link shapes.
    pub hand: Vec<f64>,
    /// The TCP origin (a held object adds its own extent).
    pub tcp: Vec<f64>,
    /// Whether each joint is prismatic.
    pub prismatic: Vec<bool>,
}

/// A scene object prepared for checking.
#[derive(Debug, Clone)]
struct Obstacle {
    name: String,
    shape: SharedShape,
    pose: Pose,
    min: Vector3<f64>,
    max: Vector3<f64>,
}

/// An object held in the hand: it moves rigidly with the TCP.
#[derive(Debug, Clone)]
pub struct Held {
    /// The object's name.
    pub name: String,
    /// The object's shape.
    pub shape: Shape,
    /// The object's pose in the TCP frame.
    pub in_tcp: Pose,
    grown: SharedShape,
    local: Pose,
    radius: f64,
}

/// What a check found in collision.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Hit {
    /// Two links of the robot.
    SelfCollision(String, String),
    /// A link and a world object.
    World(String, String),
    /// The held object and a world object.
    HeldWorld(String, String),
    /// The held object and a link.
    HeldRobot(String, String),
    /// A configuration outside the joint limits.
    Limits,
}

impl fmt::Display for Hit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Hit::SelfCollision(a, b) => write!(f, "{a} with {b}"),
            Hit::World(l, o) => write!(f, "{l} with {o}"),
            Hit::HeldWorld(h, o) => write!(f, "held {h} with {o}"),
            Hit::HeldRobot(h, l) => write!(f, "held {h} with {l}"),
            Hit::Limits => f.write_str("joint limits"),
        }
    }
}

/// Contacts allowed during part of a plan (see the module documentation of `task`).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Allowances {
    /// World objects the hand links may touch (the object being grasped or just released).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hand_may_touch: Vec<String>,
    /// World objects the held object may touch (the support it leaves or is placed on).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_may_touch: Vec<String>,
}

impl Allowances {
    /// Whether nothing is allowed.
    pub fn is_empty(&self) -> bool {
        self.hand_may_touch.is_empty() && self.held_may_touch.is_empty()
    }
}

impl RobotCollision {
    /// Prepares the robot's shapes, self-collision pairs and reach bounds with the margins of
    /// its `robot.toml`.
    pub fn new(robot: &Robot) -> RobotCollision {
        let c = &robot.config().collision;
        let margins = Margins {
            arm: c.arm_margin,
            hand: c.hand_margin,
            held: c.held_margin,
            self_: c.self_margin,
        };
        Self::with_margins(robot, margins)
    }

    /// The same with other margins (e.g. to re-check a plan with the clearance it guarantees).
    pub fn with_margins(robot: &Robot, margins: Margins) -> RobotCollision {
        let mut bodies = Vec::new();
        for (i, link) in robot.links().iter().enumerate() {
            let group = if robot.hand_links().contains(&i) {
                Group::Hand
            } else {
                Group::Arm
            };
            let margin = match group {
                Group::Arm => margins.arm,
                Group::Hand => margins.hand,
            };
            for s in &link.shapes {
                let (world_shape, fix) = parry_convert::robot_shape(&s.geometry, margin);
                let (self_shape, _) = parry_convert::robot_shape(&s.geometry, 0.5 * margins.self_);
                let (half_segment, core) = match s.geometry {
                    Geometry::Capsule { radius, length } => (0.5 * length, radius),
                    other => (0.0, other.bounding_radius()),
                };
                bodies.push(Body {
                    link: i,
                    group,
                    local: s.origin * fix,
                    world_shape,
                    self_shape,
                    half_segment,
                    world_radius: core + margin,
                    self_radius: core + 0.5 * margins.self_,
                });
            }
        }
        let allowed = |a: usize, b: usize| {
            a == b
                || robot
                    .allowed_pairs()
                    .iter()
                    .any(|&(x, y)| (x, y) == (a, b) || (y, x) == (a, b))
        };
        let mut self_pairs = Vec::new();
        for i in 0..bodies.len() {
            for j in i + 1..bodies.len() {
                if !allowed(bodies[i].link, bodies[j].link) {
                    self_pairs.push((i, j));
                }
            }
        }
        let reach = Reach::new(robot.kinematics(), &bodies);
        RobotCollision {
            bodies,
            self_pairs,
            mount_links: robot.mount_links().to_vec(),
            margins,
            reach,
            tcp: robot.tcp_link(),
        }
    }

    /// The margins in use.
    pub fn margins(&self) -> Margins {
        self.margins
    }

    /// The per-joint reach bounds.
    pub fn reach(&self) -> &Reach {
        &self.reach
    }

    /// Number of link pairs tested against each other.
    pub fn self_pair_count(&self) -> usize {
        self.self_pairs.len()
    }
}

impl Reach {
    fn new(kin: &Kinematics, bodies: &[Body]) -> Reach {
        let links = kin.links();
        // Distance bound from a link's frame origin to the origin of each descendant: the sum
        // of the joint offsets along the way.
        let chain_length = |from: usize, to: usize| -> Option<f64> {
            let mut length = 0.0;
            let mut at = to;
            while at != from {
                length += links[at].origin.translation.vector.norm();
                at = links[at].parent?;
            }
            Some(length)
        };
        let dof = kin.dof();
        let mut reach = Reach {
            arm: vec![0.0; dof],
            hand: vec![0.0; dof],
            tcp: vec![0.0; dof],
            prismatic: vec![false; dof],
        };
        for (j, &joint_link) in kin.arm_links().iter().enumerate() {
            reach.prismatic[j] = matches!(
                links[joint_link].motion,
                crate::fk::Motion::Prismatic { .. }
            );
            for b in bodies {
                if let Some(d) = chain_length(joint_link, b.link) {
                    let r = d + b.local.translation.vector.norm() + b.half_segment + b.world_radius;
                    let slot = match b.group {
                        Group::Arm => &mut reach.arm[j],
                        Group::Hand => &mut reach.hand[j],
                    };
                    *slot = slot.max(r);
                }
            }
            if let Some(d) = chain_length(joint_link, kin.tcp_index()) {
                reach.tcp[j] = d;
            }
        }
        reach
    }

    /// Upper bound on how far any point of each group moves when the arm goes in a straight
    /// joint-space line from `a` to `b`: (arm, hand, held object of extent `held_radius`
    /// about the TCP).
    pub fn displacement(&self, a: &[f64], b: &[f64], held_radius: f64) -> [f64; 3] {
        let mut d = [0.0; 3];
        for j in 0..a.len() {
            let dq = (b[j] - a[j]).abs();
            if self.prismatic[j] {
                for v in &mut d {
                    *v += dq;
                }
            } else {
                d[0] += self.arm[j] * dq;
                d[1] += self.hand[j] * dq;
                d[2] += (self.tcp[j] + held_radius) * dq;
            }
        }
        d
    }
}

impl Held {
    /// An object of `shape` held with pose `in_tcp` in the TCP frame, grown by `margin`.
    pub fn new(name: &str, shape: Shape, in_tcp: Pose, margin: f64) -> Held {
        let (grown, local) = parry_convert::object_shape(&shape, margin);
        let h = shape.half_extents();
        Held {
            name: name.to_string(),
            shape,
            in_tcp,
            grown,
            local,
            radius: in_tcp.translation.vector.norm() + h.norm() + margin,
        }
    }

    /// Radius of a ball about the TCP that holds the (grown) object.
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

/// The world as the checker sees it: exact object shapes with bounding boxes, the robot's
/// base pose, and the object the robot stands on.
#[derive(Debug, Clone)]
pub struct Scene {
    obstacles: Vec<Obstacle>,
    base: Pose,
    mount: Option<usize>,
}

impl Scene {
    /// The objects of `world` except those named in `without` (e.g. a held object).
    pub fn new(world: &World, without: &[&str]) -> Scene {
        let mut obstacles = Vec::new();
        for o in world
            .objects
            .iter()
            .filter(|o| !without.contains(&o.name.as_str()))
        {
            let (shape, fix) = parry_convert::object_shape(&o.shape, 0.0);
            let h = o.shape.world_half_extents(&o.pose);
            let c = o.pose.translation.vector;
            obstacles.push(Obstacle {
                name: o.name.clone(),
                shape,
                pose: o.pose * fix,
                min: c - h,
                max: c + h,
            });
        }
        let base = world.robot_base;
        let origin = base.translation.vector;
        let mount = obstacles.iter().position(|o| {
            let inside = |i: usize| origin[i] >= o.min[i] - 1e-9 && origin[i] <= o.max[i] + 1e-9;
            inside(0) && inside(1) && (o.max.z - origin.z).abs() <= akl_scene::world::SUPPORT_GAP
        });
        Scene {
            obstacles,
            base,
            mount,
        }
    }

    /// The robot base pose in the world.
    pub fn base(&self) -> &Pose {
        &self.base
    }

    /// Name of the object the robot is mounted on, if any.
    pub fn mount(&self) -> Option<&str> {
        self.mount.map(|i| self.obstacles[i].name.as_str())
    }
}

/// A capsule-like body in world coordinates: a segment and a radius.
#[derive(Debug, Clone, Copy, Default)]
struct Placed {
    pose: Pose,
    a: Vector3<f64>,
    b: Vector3<f64>,
}

fn placed(body: &Body, link_pose: &Pose) -> Placed {
    let pose = link_pose * body.local;
    let a = (pose * Point3::new(0.0, 0.0, -body.half_segment)).coords;
    let b = (pose * Point3::new(0.0, 0.0, body.half_segment)).coords;
    Placed { pose, a, b }
}

fn box_overlap(p: &Placed, r: f64, min: &Vector3<f64>, max: &Vector3<f64>) -> bool {
    (0..3).all(|i| p.a[i].min(p.b[i]) - r <= max[i] && p.a[i].max(p.b[i]) + r >= min[i])
}

/// Squared distance between segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision
/// Detection, §5.1.9), for the cheap rejection of far link pairs.
fn segment_distance_sq(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> f64 {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t);
    if a <= 1e-12 && e <= 1e-12 {
        return r.dot(&r);
    }
    if a <= 1e-12 {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= 1e-12 {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s0 = if denom > 1e-12 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    let c1 = p1 + d1 * s;
    let c2 = p2 + d2 * t;
    (c1 - c2).norm_squared()
}

/// Checks configurations of one robot in one scene.
#[derive(Debug, Clone)]
pub struct Checker<'a> {
    robot: &'a Robot,
    model: &'a RobotCollision,
    scene: &'a Scene,
}

impl<'a> Checker<'a> {
    /// A checker for `robot` (with its prepared `model`) in `scene`.
    pub fn new(robot: &'a Robot, model: &'a RobotCollision, scene: &'a Scene) -> Self {
        Checker {
            robot,
            model,
            scene,
        }
    }

    /// The robot.
    pub fn robot(&self) -> &'a Robot {
        self.robot
    }

    /// The robot's collision model.
    pub fn model(&self) -> &'a RobotCollision {
        self.model
    }

    /// The scene.
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The first collision of configuration `q` with gripper opening `width`, holding `held`
    /// (if any), under `allow`; `None` if it is collision-free and within the joint limits.
    pub fn check(
        &self,
        q: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
    ) -> Option<Hit> {
        let within = q
            .iter()
            .zip(self.robot.joint_limits())
            .all(|(v, [lo, hi])| *v >= *lo && *v <= *hi);
        if !within {
            return Some(Hit::Limits);
        }
        let links = self.robot.links();
        let n = links.len().min(MAX_LINKS);
        let mut poses = [Pose::identity(); MAX_LINKS];
        self.robot
            .kinematics()
            .link_poses_into(q, width, &mut poses[..n]);
        for p in &mut poses[..n] {
            *p = self.scene.base * *p;
        }
        let bodies = &self.model.bodies;
        let nb = bodies.len().min(MAX_BODIES);
        let mut placed_bodies = [Placed::default(); MAX_BODIES];
        for (slot, b) in placed_bodies.iter_mut().zip(bodies) {
            *slot = placed(b, &poses[b.link]);
        }
        let placed_bodies = &placed_bodies[..nb];
        // Self collision: bounding balls, then segment distance, then parry.
        for &(i, j) in &self.model.self_pairs {
            let (Some(pa), Some(pb)) = (placed_bodies.get(i), placed_bodies.get(j)) else {
                continue;
            };
            let (ba, bb) = (&bodies[i], &bodies[j]);
            let reach = ba.self_radius + bb.self_radius;
            let balls = reach + ba.half_segment + bb.half_segment;
            let centres = 0.5 * ((pa.a + pa.b) - (pb.a + pb.b));
            if centres.norm_squared() > balls * balls
                || segment_distance_sq(&pa.a, &pa.b, &pb.a, &pb.b) > reach * reach
            {
                continue;
            }
            if parry_convert::intersects(&ba.self_shape, &pa.pose, &bb.self_shape, &pb.pose) {
                return Some(Hit::SelfCollision(
                    links[ba.link].name.clone(),
                    links[bb.link].name.clone(),
                ));
            }
        }
        // Robot against the world.
        for (b, p) in bodies.iter().zip(placed_bodies) {
            for (k, o) in self.scene.obstacles.iter().enumerate() {
                if Some(k) == self.scene.mount && self.model.mount_links.contains(&b.link) {
                    continue;
                }
                if b.group == Group::Hand && allow.hand_may_touch.contains(&o.name) {
                    continue;
                }
                if !box_overlap(p, b.world_radius, &o.min, &o.max) {
                    continue;
                }
                if parry_convert::intersects(&b.world_shape, &p.pose, &o.shape, &o.pose) {
                    return Some(Hit::World(links[b.link].name.clone(), o.name.clone()));
                }
            }
        }
        // The held object against the world and the arm.
        if let Some(h) = held {
            let pose = poses[self.model.tcp] * h.in_tcp * h.local;
            let centre = (poses[self.model.tcp] * h.in_tcp).translation.vector;
            let ball = Placed {
                pose,
                a: centre,
                b: centre,
            };
            for o in &self.scene.obstacles {
                if allow.held_may_touch.contains(&o.name) {
                    continue;
                }
                if !box_overlap(
                    &ball,
                    h.radius - h.in_tcp.translation.vector.norm(),
                    &o.min,
                    &o.max,
                ) {
                    continue;
                }
                if parry_convert::intersects(&h.grown, &pose, &o.shape, &o.pose) {
                    return Some(Hit::HeldWorld(h.name.clone(), o.name.clone()));
                }
            }
            let extent = h.radius - h.in_tcp.translation.vector.norm();
            for (b, p) in bodies.iter().zip(placed_bodies) {
                if b.group == Group::Hand {
                    continue;
                }
                let reach = extent + b.self_radius;
                if segment_distance_sq(&p.a, &p.b, &centre, &centre) > reach * reach {
                    continue;
                }
                if parry_convert::intersects(&b.self_shape, &p.pose, &h.grown, &pose) {
                    return Some(Hit::HeldRobot(h.name.clone(), links[b.link].name.clone()));
                }
            }
        }
        None
    }

    /// Whether `q` is collision-free (see [`Checker::check`]).
    pub fn is_free(&self, q: &[f64], width: f64, held: Option<&Held>, allow: &Allowances) -> bool {
        self.check(q, width, held, allow).is_none()
    }

    /// How many checks the straight joint-space edge from `a` to `b` needs so that no point of
    /// the arm, hand or held object moves more than its own margin between two checks; then
    /// the clearance never drops below half the margin anywhere along the edge (see
    /// [`Checker::edge`]).
    pub fn edge_steps(&self, a: &[f64], b: &[f64], held: Option<&Held>) -> usize {
        let m = self.model.margins;
        let d = self
            .model
            .reach
            .displacement(a, b, held.map_or(0.0, |h| h.radius));
        let mut steps = (d[0] / m.arm).max(d[1] / m.hand);
        if held.is_some() {
            steps = steps.max(d[2] / m.held);
        }
        (steps.ceil() as usize).max(1)
    }

    /// The first collision on the straight joint-space edge from `a` to `b` (endpoints
    /// included), checked at [`Checker::edge_steps`] evenly spaced configurations in
    /// bisection order so that collisions are found early.
    ///
    /// Resolution: between two neighbouring checks every point of a group moves at most that
    /// group's margin m, so at any intermediate configuration each point is within m/2 of
    /// where it was at the nearer check; the clearance to the world therefore stays at least
    /// m/2 all along the edge, and two links grown by half the self margin each (≥ the arm
    /// margin) never interpenetrate.
    pub fn edge(
        &self,
        a: &[f64],
        b: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
    ) -> Option<Hit> {
        let steps = self.edge_steps(a, b, held);
        let mut q = vec![0.0; a.len()];
        let mut at = |k: usize| -> Option<Hit> {
            let t = k as f64 / steps as f64;
            for (i, v) in q.iter_mut().enumerate() {
                *v = a[i] + t * (b[i] - a[i]);
            }
            self.check(&q, width, held, allow)
        };
        if let Some(hit) = at(steps).or_else(|| at(0)) {
            return Some(hit);
        }
        // Bisection order: midpoints of ever finer subdivisions.
        let mut stride = steps.next_power_of_two();
        while stride > 1 {
            let half = stride / 2;
            let mut k = half;
            while k < steps {
                if let Some(hit) = at(k) {
                    return Some(hit);
                }
                k += stride;
            }
            stride = half;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::pose::pose_from_xyz_rpy;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    fn none() -> Allowances {
        Allowances::default()
    }

    #[test]
    fn the_ready_pose_is_free_in_every_task_and_the_table_is_the_mount() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        for name in builtin::names() {
            let task = builtin::task(name).unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            assert_eq!(scene.mount(), Some("table"));
            let checker = Checker::new(&robot, &model, &scene);
            assert_eq!(
                checker.check(robot.ready(), 0.08, None, &none()),
                None,
                "{name}"
            );
        }
    }

    #[test]
    fn the_hand_in_the_table_is_a_collision_named_by_link_and_object() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let scene = Scene::new(&task.world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let low = pose_from_xyz_rpy([0.65, 0.0, 0.01], [PI, 0.0, 0.0]);
        let q = robot.ik(&low, robot.ready()).unwrap();
        match checker.check(&q, 0.08, None, &none()) {
            Some(Hit::World(link, object)) => {
                assert!(link.contains("finger") || link.contains("hand"), "{link}");
                assert_eq!(object, "table");
            }
            other => panic!("expected the hand on the table, got {other:?}"),
        }
        assert_eq!(
            checker.check(
                &q,
                0.08,
                None,
                &Allowances {
                    hand_may_touch: vec!["table".into()],
                    held_may_touch: vec![],
                }
            ),
            None
        );
    }

    #[test]
    fn self_collisions_name_two_links_that_may_not_touch() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let scene = Scene::new(
            &World {
                robot_base: Pose::identity(),
                objects: vec![],
            },
            &[],
        );
        let checker = Checker::new(&robot, &model, &scene);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut found = 0;
        for _ in 0..500 {
            let q: Vec<f64> = robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            if let Some(Hit::SelfCollision(a, b)) = checker.check(&q, 0.08, None, &none()) {
                found += 1;
                let allowed = robot
                    .config()
                    .collision
                    .allowed_pairs
                    .iter()
                    .any(|[x, y]| (x == &a && y == &b) || (x == &b && y == &a));
                assert!(!allowed && a != b, "{a} with {b}");
            }
        }
        assert!(found > 0);
        let out = [0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0];
        assert_eq!(checker.check(&out, 0.08, None, &none()), Some(Hit::Limits));
    }

    #[test]
    fn a_held_block_collides_with_its_support_unless_allowed() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let task = builtin::task("pick_place").unwrap().unwrap();
        let block = task.world.object("block_a").unwrap();
        let grasp = block.pose * pose_from_xyz_rpy([0.0, 0.0, 0.015], [PI, 0.0, 0.0]);
        let q = robot.ik(&grasp, robot.ready()).unwrap();
        let held = Held::new("block_a", block.shape, grasp.inverse() * block.pose, 0.001);
        let scene = Scene::new(&task.world, &["block_a"]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(
            checker.check(&q, 0.05, Some(&held), &none()),
            Some(Hit::HeldWorld("block_a".into(), "shelf_1".into()))
        );
        let allow = Allowances {
            hand_may_touch: vec![],
            held_may_touch: vec!["shelf_1".into()],
        };
        assert_eq!(checker.check(&q, 0.05, Some(&held), &allow), None);
    }

    fn arb_q() -> impl Strategy<Value = Vec<f64>> {
        let robot = Robot::panda().unwrap();
        robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| *lo..*hi)
            .collect::<Vec<_>>()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// An edge reported free keeps half of every margin at a 10x denser re-check.
        #[test]
        fn free_edges_keep_half_their_margins_everywhere(a in arb_q(), b in arb_q(), t in 0.0..1.0f64) {
            let robot = Robot::panda().unwrap();
            let model = RobotCollision::new(&robot);
            let m = model.margins();
            let half = RobotCollision::with_margins(&robot, Margins {
                arm: m.arm / 2.0, hand: m.hand / 2.0, held: m.held / 2.0, self_: 1e-9,
            });
            let task = builtin::task("inspection").unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            let dense = Checker::new(&robot, &half, &scene);
            // Shorten the edge so that a good share of them are free.
            let b: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + t * 0.5 * (y - x)).collect();
            if checker.edge(&a, &b, 0.08, None, &none()).is_none() {
                let n = 10 * checker.edge_steps(&a, &b, None);
                for k in 0..=n {
                    let s = k as f64 / n as f64;
                    let q: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + s * (y - x)).collect();
                    prop_assert_eq!(dense.check(&q, 0.08, None, &none()), None);
                }
            }
        }
    }
}
