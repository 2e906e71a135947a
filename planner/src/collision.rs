//! Collision checking of the arm, the hand and a held object against the world and the arm
//! itself, with parry3d shapes and cheap bounding-box culling before each exact test.
//!
//! Margins (from `robot.toml`): arm links are grown by `arm_margin`, hand links by
//! `hand_margin` and a held object by `held_margin` before being tested against the exact
//! world objects; two links are each grown by half of `self_margin` before being tested
//! against each other. Link pairs in `allowed_pairs` are never tested, nor `mount_links`
//! against the object under the robot base.
//!
//! Edges (straight joint-space segments, [`Checker::edge`]) are checked continuously in the
//! following sense: every clearance keeps at least half its margin everywhere along an edge
//! reported free. Each check on the edge proves a stretch around it free, as long as the
//! stretch is short enough that no point moves further than the clearance found at the
//! check plus half the margin. How far points move is bounded per collision element by
//! [`Checker::sweep_bound`]: turning joint j by Δ moves a point at distance r from its axis by
//! at most r·|Δ|, where r is measured at the check and may grow along the stretch by what the
//! joints beyond j move the point.

use crate::contact_rules::{self, Allowances, LinkRole};
use crate::fk::{Drive, Kinematics, Motion};
use crate::geometry::Geometry;
use crate::hand::HandModel;
use crate::parry_convert;
use crate::robot::{Robot, MAX_BODIES, MAX_LINKS};
use akl_scene::{Shape, World};
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use parry3d::shape::SharedShape;
use std::collections::VecDeque;
use std::fmt;

/// What parry's single-precision distances are trusted to (metres): clearances it reports
/// are reduced by this much before they are relied on.
const DISTANCE_TOLERANCE: f64 = 1e-5;

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
    /// Half the capsule's segment (0 for other shapes), and the radii of balls around the
    /// segment that hold the shape itself, the shape grown by the group's margin and the
    /// shape grown by half the self margin.
    half_segment: f64,
    core_radius: f64,
    world_radius: f64,
    self_radius: f64,
}

/// A joint that moves a collision element when the arm moves: the link it turns or slides,
/// the arm joint that drives it and by how much, and its axis in the link frame.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Mover {
    link: usize,
    index: usize,
    scale: f64,
    /// `None` for a prismatic joint.
    axis: Option<Vector3<f64>>,
}

/// The robot's collision model: its shapes, the link pairs to test and the joint chains used
/// to bound how far they move along edges.
#[derive(Debug, Clone)]
pub struct RobotCollision {
    bodies: Vec<Body>,
    self_pairs: Vec<(usize, usize)>,
    mount_links: Vec<usize>,
    margins: Margins,
    tcp: usize,
    /// For each body, then for the TCP: the arm-driven joints from the base to its link.
    chains: Vec<Vec<Mover>>,
    /// Where each chain's motion bounds start in a [`Sweep`]'s `bounds`.
    offsets: Vec<usize>,
    /// For each self pair, how many leading joints of their chains the two bodies share.
    self_shared: Vec<usize>,
    /// For each body, how many leading joints its chain shares with the TCP's.
    tcp_shared: Vec<usize>,
    /// The links turned by arm-driven revolute joints, with their axes in the link frame.
    turned: Vec<(usize, Vector3<f64>)>,
}

/// Every collision element of `robot` as (link, geometry, pose in the link frame): the URDF's
/// shapes, and the simulated hand's palm and pads ([`crate::hand`]), whose box corners reach
/// past the URDF's capsules: the planner keeps clear whatever the simulated hand can touch.
fn collision_elements(robot: &Robot) -> Vec<(usize, Geometry, Pose)> {
    let urdf = robot
        .links()
        .iter()
        .enumerate()
        .flat_map(|(i, link)| link.shapes.iter().map(move |s| (i, s.geometry, s.origin)));
    let hand = HandModel::new(robot).map(|h| h.boxes()).unwrap_or_default();
    urdf.chain(hand).collect()
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
    exact: SharedShape,
    local: Pose,
    margin: f64,
    /// Radius of a ball about the object's centre that holds the object itself.
    core: f64,
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

/// The arm-driven joints between the base and `link`, base first.
fn chain_to(kin: &Kinematics, link: usize) -> Vec<Mover> {
    let links = kin.links();
    let mut chain = Vec::new();
    let mut at = Some(link);
    while let Some(i) = at {
        let (axis, drive) = match links[i].motion {
            Motion::Revolute { axis, drive } => (Some(axis.into_inner()), drive),
            Motion::Prismatic { drive, .. } => (None, drive),
            Motion::Fixed => (None, Drive::Constant(0.0)),
        };
        if let Drive::Arm { index, scale, .. } = drive {
            chain.push(Mover {
                link: i,
                index,
                scale,
                axis,
            });
        }
        at = links[i].parent;
    }
    chain.reverse();
    chain
}

/// How many leading joints two chains share.
fn shared(a: &[Mover], b: &[Mover]) -> usize {
    a.iter()
        .zip(b)
        .take_while(|(x, y)| x.link == y.link)
        .count()
}

impl RobotCollision {
    /// Prepares the robot's shapes, self-collision pairs and joint chains with the margins of
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
        for (i, geometry, origin) in collision_elements(robot) {
            let group = if robot.hand_links().contains(&i) {
                Group::Hand
            } else {
                Group::Arm
            };
            let margin = match group {
                Group::Arm => margins.arm,
                Group::Hand => margins.hand,
            };
            let (world_shape, fix) = parry_convert::robot_shape(&geometry, margin);
            let (self_shape, _) = parry_convert::robot_shape(&geometry, 0.5 * margins.self_);
            let (half_segment, core) = match geometry {
                Geometry::Capsule { radius, length } => (0.5 * length, radius),
                other => (0.0, other.bounding_radius()),
            };
            bodies.push(Body {
                link: i,
                group,
                local: origin * fix,
                world_shape,
                self_shape,
                half_segment,
                core_radius: core,
                world_radius: core + margin,
                self_radius: core + 0.5 * margins.self_,
            });
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
        let kin = robot.kinematics();
        let tcp = robot.tcp_link();
        let mut chains: Vec<Vec<Mover>> = bodies.iter().map(|b| chain_to(kin, b.link)).collect();
        chains.push(chain_to(kin, tcp));
        let mut offsets = Vec::with_capacity(chains.len() + 1);
        let mut next = 0;
        for chain in &chains {
            offsets.push(next);
            next += chain.len() + 1;
        }
        offsets.push(next);
        let tcp_chain = &chains[bodies.len()];
        let self_shared = self_pairs
            .iter()
            .map(|&(i, j)| shared(&chains[i], &chains[j]))
            .collect();
        let tcp_shared = chains[..bodies.len()]
            .iter()
            .map(|c| shared(c, tcp_chain))
            .collect();
        let mut turned: Vec<(usize, Vector3<f64>)> = chains
            .iter()
            .flatten()
            .filter_map(|m| m.axis.map(|axis| (m.link, axis)))
            .collect();
        turned.sort_by_key(|(link, _)| *link);
        turned.dedup_by_key(|(link, _)| *link);
        RobotCollision {
            bodies,
            self_pairs,
            mount_links: robot.mount_links().to_vec(),
            margins,
            tcp,
            chains,
            offsets,
            self_shared,
            tcp_shared,
            turned,
        }
    }

    /// The margins in use.
    pub fn margins(&self) -> Margins {
        self.margins
    }

    /// Number of link pairs tested against each other.
    pub fn self_pair_count(&self) -> usize {
        self.self_pairs.len()
    }
}

impl Held {
    /// An object of `shape` held with pose `in_tcp` in the TCP frame, grown by `margin`.
    pub fn new(name: &str, shape: Shape, in_tcp: Pose, margin: f64) -> Held {
        let (grown, local) = parry_convert::object_shape(&shape, margin);
        let (exact, _) = parry_convert::object_shape(&shape, 0.0);
        let core = shape.half_extents().norm();
        Held {
            name: name.to_string(),
            shape,
            in_tcp,
            grown,
            exact,
            local,
            margin,
            core,
            radius: in_tcp.translation.vector.norm() + core + margin,
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

#[inline(always)]
fn placed(body: &Body, link_pose: &Pose) -> Placed {
    let pose = link_pose * body.local;
    let a = (pose * Point3::new(0.0, 0.0, -body.half_segment)).coords;
    let b = (pose * Point3::new(0.0, 0.0, body.half_segment)).coords;
    Placed { pose, a, b }
}

/// The world-axis-aligned box around `p` grown by `r`: its lower and upper corners.
fn bounding_box(p: &Placed, r: f64) -> [Vector3<f64>; 2] {
    let grow = Vector3::repeat(r);
    [p.a.inf(&p.b) - grow, p.a.sup(&p.b) + grow]
}

/// Squared distance between two world-axis-aligned boxes (0 when they overlap).
fn box_gap_sq(a: &[Vector3<f64>; 2], min: &Vector3<f64>, max: &Vector3<f64>) -> f64 {
    (a[0] - max)
        .sup(&(min - a[1]))
        .sup(&Vector3::zeros())
        .norm_squared()
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

/// Work space of an edge check: the joint motion of the stretch being proved free and the
/// motion bounds derived from it.
struct Sweep {
    /// How far each arm joint turns or slides from the check to either end of the stretch.
    half: Vec<f64>,
    /// For each chain k of the model, `bounds[offsets[k] + m]` bounds how far any point of
    /// its element moves through the joints `m..` of the chain (0 past the last one).
    bounds: Vec<f64>,
}

impl Sweep {
    fn new(model: &RobotCollision, dof: usize) -> Sweep {
        Sweep {
            half: vec![0.0; dof],
            bounds: vec![0.0; model.offsets.last().copied().unwrap_or(0)],
        }
    }
}

/// Tracks, during one check, how much of a stretch its clearances prove free: the fraction
/// of the stretch (up to 1) over which no element moves further than its clearance plus
/// half its margin.
struct Proof<'s> {
    sweep: &'s Sweep,
    offsets: &'s [usize],
    fraction: f64,
}

impl Proof<'_> {
    /// Bound on how far chain `k` moves through its joints from `from` on.
    fn moved(&self, k: usize, from: usize) -> f64 {
        self.sweep.bounds[self.offsets[k] + from]
    }

    /// Whether a clearance larger than 0 would shorten nothing: an element moving `moved`
    /// with `slack` to spare is already within the current fraction.
    fn settled(&self, moved: f64, slack: f64) -> bool {
        moved * self.fraction <= slack
    }

    /// Limits the fraction to what `slack` (clearance plus half the margin) allows an element
    /// moving up to `moved` over the whole stretch.
    fn limit(&mut self, moved: f64, slack: f64) {
        if moved * self.fraction > slack {
            self.fraction = slack / moved;
        }
    }
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
        if !self.within_limits(q) {
            return Some(Hit::Limits);
        }
        self.probe::<false>(q, width, held, allow, None).err()
    }

    fn within_limits(&self, q: &[f64]) -> bool {
        q.iter()
            .zip(self.robot.joint_limits())
            .all(|(v, [lo, hi])| *v >= *lo && *v <= *hi)
    }

    /// Whether `q` is collision-free (see [`Checker::check`]).
    pub fn is_free(&self, q: &[f64], width: f64, held: Option<&Held>, allow: &Allowances) -> bool {
        self.check(q, width, held, allow).is_none()
    }

    /// Writes into `sweep.bounds` the motion bounds of every chain for the joint motion
    /// `sweep.half` about the configuration whose link poses are `poses`.
    ///
    /// Going from the last joint of a chain to the first, with D the bound through the joints
    /// beyond joint j: the point stays within r + D of joint j's axis, r being its distance
    /// at the configuration (the element's centre's distance plus the element's extent), so
    /// turning joint j by Δ adds (r + D)·|Δ|; sliding it adds |Δ|.
    fn sweep_bounds(
        &self,
        poses: &[Pose],
        placed_bodies: &[Placed],
        held: Option<&Held>,
        sweep: &mut Sweep,
    ) {
        let model = self.model;
        let tcp = poses[model.tcp];
        let mut axes = [Vector3::zeros(); MAX_LINKS];
        for &(link, axis) in &model.turned {
            axes[link] = poses[link].rotation * axis;
        }
        for (k, chain) in model.chains.iter().enumerate() {
            let (centre, extent) = match (placed_bodies.get(k), model.bodies.get(k)) {
                (Some(p), Some(b)) => (p.pose.translation.vector, b.half_segment + b.core_radius),
                _ => match held {
                    Some(h) => ((tcp * h.in_tcp).translation.vector, h.core),
                    None => (tcp.translation.vector, 0.0),
                },
            };
            let slots = &mut sweep.bounds[model.offsets[k]..model.offsets[k + 1]];
            let mut d = 0.0;
            slots[chain.len()] = d;
            for (m, mover) in chain.iter().enumerate().rev() {
                let turn = mover.scale.abs() * sweep.half[mover.index];
                d += if mover.axis.is_some() {
                    let origin = poses[mover.link].translation.vector;
                    let r = (centre - origin).cross(&axes[mover.link]).norm() + extent;
                    (r + d) * turn
                } else {
                    turn
                };
                slots[m] = d;
            }
        }
    }

    /// Upper bound on how far any point of the robot's collision elements, or of `held`,
    /// moves when the arm goes in a straight joint-space line from `a` to `b` with gripper
    /// opening `width` (the bound of [`Checker::edge`], taken about the edge's midpoint).
    pub fn sweep_bound(&self, a: &[f64], b: &[f64], width: f64, held: Option<&Held>) -> f64 {
        let mid: Vec<f64> = a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect();
        let n = self.robot.links().len().min(MAX_LINKS);
        let mut poses = [Pose::identity(); MAX_LINKS];
        self.robot
            .kinematics()
            .link_poses_into(&mid, width, &mut poses[..n]);
        let mut placed_bodies = [Placed::default(); MAX_BODIES];
        for (slot, body) in placed_bodies.iter_mut().zip(&self.model.bodies) {
            *slot = placed(body, &poses[body.link]);
        }
        let nb = self.model.bodies.len().min(MAX_BODIES);
        let mut sweep = Sweep::new(self.model, a.len());
        for (h, (x, y)) in sweep.half.iter_mut().zip(a.iter().zip(b)) {
            *h = 0.5 * (y - x).abs();
        }
        self.sweep_bounds(&poses[..n], &placed_bodies[..nb], held, &mut sweep);
        let last = self.model.chains.len() - if held.is_some() { 0 } else { 1 };
        (0..last)
            .map(|k| sweep.bounds[self.model.offsets[k]])
            .fold(0.0, f64::max)
            * 2.0
    }

    /// The first collision of `q` (within the joint limits), or, when `PROVE` is set and
    /// `sweep` holds the joint motion of a stretch about `q`, the fraction of that stretch
    /// proved free (see the module documentation). Plain checks are compiled without the
    /// proof's work.
    fn probe<const PROVE: bool>(
        &self,
        q: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
        sweep: Option<&mut Sweep>,
    ) -> Result<f64, Hit> {
        let links = self.robot.links();
        let n = links.len().min(MAX_LINKS);
        let mut poses = [Pose::identity(); MAX_LINKS];
        self.robot
            .kinematics()
            .link_poses_into(q, width, &mut poses[..n]);
        for p in &mut poses[..n] {
            *p = self.scene.base * *p;
        }
        let model = self.model;
        let bodies = &model.bodies;
        let nb = bodies.len().min(MAX_BODIES);
        let mut placed_bodies = [Placed::default(); MAX_BODIES];
        for (slot, b) in placed_bodies.iter_mut().zip(bodies) {
            *slot = placed(b, &poses[b.link]);
        }
        let placed_bodies = &placed_bodies[..nb];
        let mut proof = sweep.filter(|_| PROVE).map(|s| {
            self.sweep_bounds(&poses[..n], placed_bodies, held, s);
            Proof {
                sweep: s,
                offsets: &model.offsets,
                fraction: 1.0,
            }
        });
        let m = model.margins;
        // Self collision: bounding balls, then segment distance, then parry.
        let self_slack = 0.5 * m.self_;
        for (p, &(i, j)) in model.self_pairs.iter().enumerate() {
            let (Some(pa), Some(pb)) = (placed_bodies.get(i), placed_bodies.get(j)) else {
                continue;
            };
            let (ba, bb) = (&bodies[i], &bodies[j]);
            let reach = ba.self_radius + bb.self_radius;
            let balls = reach + ba.half_segment + bb.half_segment;
            let centres = 0.5 * ((pa.a + pa.b) - (pb.a + pb.b));
            let moved = proof.as_ref().map_or(0.0, |pr| {
                let s = model.self_shared[p];
                pr.moved(i, s) + pr.moved(j, s)
            });
            let centres_sq = centres.norm_squared();
            if let Some(pr) = proof.as_mut() {
                // The distance of the bounding balls first, the segments' only if it matters.
                let balls_gap = centres_sq.sqrt() - balls;
                if balls_gap > 0.0 && pr.settled(moved, self_slack + balls_gap) {
                    continue;
                }
                let gap = segment_distance_sq(&pa.a, &pa.b, &pb.a, &pb.b).sqrt() - reach;
                if gap > 0.0 {
                    pr.limit(moved, self_slack + gap);
                    continue;
                }
            } else if centres_sq > balls * balls
                || segment_distance_sq(&pa.a, &pa.b, &pb.a, &pb.b) > reach * reach
            {
                continue;
            }
            if parry_convert::intersects(&ba.self_shape, &pa.pose, &bb.self_shape, &pb.pose) {
                return Err(Hit::SelfCollision(
                    links[ba.link].name.clone(),
                    links[bb.link].name.clone(),
                ));
            }
            if let Some(pr) = proof.as_mut() {
                pr.limit(moved, self_slack);
            }
        }
        // Robot against the world.
        for (k, (b, p)) in bodies.iter().zip(placed_bodies).enumerate() {
            let slack = 0.5
                * match b.group {
                    Group::Arm => m.arm,
                    Group::Hand => m.hand,
                };
            let moved = proof.as_ref().map_or(0.0, |pr| pr.moved(k, 0));
            let bounds = bounding_box(p, b.world_radius);
            let role = LinkRole {
                hand: b.group == Group::Hand,
                mount: model.mount_links.contains(&b.link),
            };
            for o in &self.scene.obstacles {
                if contact_rules::link_may_touch(role, &o.name, None, self.scene.mount(), allow) {
                    continue;
                }
                if !clear_of(&b.world_shape, p, &bounds, o, proof.as_mut(), moved, slack) {
                    return Err(Hit::World(links[b.link].name.clone(), o.name.clone()));
                }
            }
        }
        // The held object against the world and the arm.
        if let Some(h) = held {
            let pose = poses[model.tcp] * h.in_tcp * h.local;
            let centre = (poses[model.tcp] * h.in_tcp).translation.vector;
            let ball = Placed {
                pose,
                a: centre,
                b: centre,
            };
            let extent = h.radius - h.in_tcp.translation.vector.norm();
            let held_chain = bodies.len();
            let moved = proof.as_ref().map_or(0.0, |pr| pr.moved(held_chain, 0));
            let bounds = bounding_box(&ball, extent);
            for o in &self.scene.obstacles {
                if contact_rules::held_may_touch(&o.name, allow) {
                    // It may rest on it, not press into it (checked where tested, not proved
                    // over edges: pressing in is deepest where a placement ends).
                    let exact = poses[model.tcp] * h.in_tcp * h.local;
                    let depth = parry_convert::penetration(&h.exact, &exact, &o.shape, &o.pose);
                    if depth.is_some_and(|d| d > contact_rules::PRESS_DEPTH) {
                        return Err(Hit::HeldWorld(h.name.clone(), o.name.clone()));
                    }
                    continue;
                }
                let slack = 0.5 * h.margin;
                if !clear_of(&h.grown, &ball, &bounds, o, proof.as_mut(), moved, slack) {
                    return Err(Hit::HeldWorld(h.name.clone(), o.name.clone()));
                }
            }
            let slack = 0.5 * (h.margin + 0.5 * m.self_);
            for (k, (b, p)) in bodies.iter().zip(placed_bodies).enumerate() {
                if b.group == Group::Hand {
                    continue;
                }
                let reach = extent + b.self_radius;
                let moved = proof.as_ref().map_or(0.0, |pr| {
                    let s = model.tcp_shared[k];
                    pr.moved(held_chain, s) + pr.moved(k, s)
                });
                let d_sq = segment_distance_sq(&p.a, &p.b, &centre, &centre);
                if d_sq > reach * reach {
                    if let Some(pr) = proof.as_mut() {
                        pr.limit(moved, slack + d_sq.sqrt() - reach);
                    }
                    continue;
                }
                if parry_convert::intersects(&b.self_shape, &p.pose, &h.grown, &pose) {
                    return Err(Hit::HeldRobot(h.name.clone(), links[b.link].name.clone()));
                }
                if let Some(pr) = proof.as_mut() {
                    pr.limit(moved, slack);
                }
            }
        }
        Ok(proof.map_or(1.0, |pr| pr.fraction))
    }

    /// The first collision on the straight joint-space edge from `a` to `b` (endpoints
    /// included), or `None` if every clearance keeps at least half its margin all along it.
    ///
    /// Each check on the edge proves a stretch about it free: no point moves further than the
    /// clearance found there plus half its margin, by the bound of [`Checker::sweep_bound`]
    /// taken at the check for the stretch (see the module documentation). Both ends are
    /// checked first, each proving a stretch into the edge; then the midpoint of what is left,
    /// and so on breadth first on either side of what each check proved, so that checks
    /// spread over the edge in bisection order and collisions are found early. Each check
    /// proves at least half the smallest margin of motion, so the number of checks is at most
    /// about the bound on how far points move divided by that.
    pub fn edge(
        &self,
        a: &[f64],
        b: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
    ) -> Option<Hit> {
        if !self.within_limits(a) || !self.within_limits(b) {
            return Some(Hit::Limits);
        }
        let mut sweep = Sweep::new(self.model, a.len());
        for (h, (x, y)) in sweep.half.iter_mut().zip(a.iter().zip(b)) {
            *h = (y - x).abs();
        }
        // Each end proves a stretch into the edge (the bound covers the whole edge about it).
        let mut ends = [0.0; 2];
        for (end, q) in ends.iter_mut().zip([b, a]) {
            match self.probe::<true>(q, width, held, allow, Some(&mut sweep)) {
                Ok(fraction) => *end = fraction,
                Err(hit) => return Some(hit),
            }
        }
        let mut open = VecDeque::new();
        if ends[0] + ends[1] < 1.0 {
            open.push_back((ends[1], 1.0 - ends[0]));
        }
        let mut q = vec![0.0; a.len()];
        while let Some((lo, hi)) = open.pop_front() {
            let mid = 0.5 * (lo + hi);
            let half = 0.5 * (hi - lo);
            for i in 0..a.len() {
                q[i] = a[i] + mid * (b[i] - a[i]);
                sweep.half[i] = half * (b[i] - a[i]).abs();
            }
            // Within the joint limits: the ends are, and the limits are a box.
            let proved = match self.probe::<true>(&q, width, held, allow, Some(&mut sweep)) {
                Ok(fraction) => half * fraction,
                Err(hit) => return Some(hit),
            };
            if proved < half {
                open.push_back((lo, mid - proved));
                open.push_back((mid + proved, hi));
            }
        }
        None
    }
}

/// Whether `shape` at `placed.pose` (inside the world-axis-aligned box `bounds`) is
/// clear of `o`; with a proof, for an element moving up to `moved` with `slack` to spare,
/// the clearance found also limits the fraction proved free.
#[inline(always)]
fn clear_of(
    shape: &SharedShape,
    placed: &Placed,
    bounds: &[Vector3<f64>; 2],
    o: &Obstacle,
    proof: Option<&mut Proof>,
    moved: f64,
    slack: f64,
) -> bool {
    let Some(pr) = proof else {
        let overlap = (0..3).all(|i| bounds[0][i] <= o.max[i] && bounds[1][i] >= o.min[i]);
        return !overlap || !parry_convert::intersects(shape, &placed.pose, &o.shape, &o.pose);
    };
    let gap_sq = box_gap_sq(bounds, &o.min, &o.max);
    if gap_sq > 0.0 {
        pr.limit(moved, slack + gap_sq.sqrt());
        return true;
    }
    if pr.settled(moved, slack) {
        return !parry_convert::intersects(shape, &placed.pose, &o.shape, &o.pose);
    }
    match parry_convert::distance(shape, &placed.pose, &o.shape, &o.pose) {
        Some(d) if d > 0.0 => {
            pr.limit(moved, slack + (d - DISTANCE_TOLERANCE).max(0.0));
            true
        }
        Some(_) => false,
        None => {
            pr.limit(moved, slack);
            !parry_convert::intersects(shape, &placed.pose, &o.shape, &o.pose)
        }
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
                    ..Allowances::default()
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
        let held = Held::new(
            "block_a",
            block.shape.clone(),
            grasp.inverse() * block.pose,
            0.001,
        );
        let scene = Scene::new(&task.world, &["block_a"]);
        let checker = Checker::new(&robot, &model, &scene);
        assert_eq!(
            checker.check(&q, 0.05, Some(&held), &none()),
            Some(Hit::HeldWorld("block_a".into(), "shelf_1".into()))
        );
        let allow = Allowances {
            held_may_touch: vec!["shelf_1".into()],
            ..Allowances::default()
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

        /// An edge reported free keeps half of every margin (between links too) at a re-check
        /// dense enough that no point moves more than a tenth of the smallest margin.
        #[test]
        fn free_edges_keep_half_their_margins_everywhere(a in arb_q(), b in arb_q(), t in 0.0..1.0f64) {
            let robot = Robot::panda().unwrap();
            let model = RobotCollision::new(&robot);
            let m = model.margins();
            let half = RobotCollision::with_margins(&robot, Margins {
                arm: m.arm / 2.0, hand: m.hand / 2.0, held: m.held / 2.0, self_: m.self_ / 2.0,
            });
            let task = builtin::task("inspection").unwrap().unwrap();
            let scene = Scene::new(&task.world, &[]);
            let checker = Checker::new(&robot, &model, &scene);
            let dense = Checker::new(&robot, &half, &scene);
            // Shorten the edge so that a good share of them are free.
            let b: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + t * 0.5 * (y - x)).collect();
            if checker.edge(&a, &b, 0.08, None, &none()).is_none() {
                let smallest = m.arm.min(m.hand).min(m.self_ / 2.0);
                let n = (10.0 * checker.sweep_bound(&a, &b, 0.08, None) / smallest).ceil() as usize;
                for k in 0..=n {
                    let s = k as f64 / n.max(1) as f64;
                    let q: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + s * (y - x)).collect();
                    prop_assert_eq!(dense.check(&q, 0.08, None, &none()), None);
                }
            }
        }
    }
}

#[cfg(test)]
mod parry_false_positive {
    use super::*;

    /// A configuration where parry's intersection test alone reports the hand's capsule
    /// (inflated by half its margin) as touching block_b while it is 2.8 mm away (found by
    /// the RRT dense re-check with seed 82996): the checker must call it free.
    #[test]
    fn a_capsule_millimetres_from_a_box_is_not_a_collision() {
        let robot = Robot::panda().unwrap();
        let full = RobotCollision::new(&robot);
        let m = full.margins;
        let half = RobotCollision::with_margins(
            &robot,
            Margins {
                arm: m.arm / 2.0,
                hand: m.hand / 2.0,
                held: m.held / 2.0,
                self_: m.self_ / 2.0,
            },
        );
        let world = akl_scene::builtin::task("pick_place")
            .unwrap()
            .unwrap()
            .world;
        let scene = Scene::new(&world, &[]);
        let q = [
            1.649183, 0.854644, -1.19825, -1.952202, -1.082712, 2.778365, -0.502894,
        ];
        let checker = Checker::new(&robot, &half, &scene);
        assert_eq!(
            checker.check(&q, robot.open_width(), None, &Allowances::default()),
            None
        );
        let n = robot.links().len();
        let mut poses = vec![Pose::identity(); n];
        robot
            .kinematics()
            .link_poses_into(&q, robot.open_width(), &mut poses);
        let block = scene
            .obstacles
            .iter()
            .find(|o| o.name == "block_b")
            .unwrap();
        let hand = half
            .bodies
            .iter()
            .find(|b| robot.links()[b.link].name == "panda_hand")
            .unwrap();
        let at = placed(hand, &(scene.base * poses[hand.link]));
        let d = parry_convert::distance(&hand.world_shape, &at.pose, &block.shape, &block.pose);
        assert!(d.unwrap() > 0.002, "{d:?}");
        assert!(!parry_convert::intersects(
            &hand.world_shape,
            &at.pose,
            &block.shape,
            &block.pose
        ));
    }
}
