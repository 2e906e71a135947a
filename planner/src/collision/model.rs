//! The robot's collision model: its bodies (collision elements grown by their margins),
//! the joints that move each, and which pairs are checked against each other.

use super::inside::inside;
use super::lanes::ChainLanes;
use super::pair_table::PairTable;
use super::spheres::Spheres;
use super::stored::StoredTables;
use crate::contact_rules::LinkRole;
use crate::fk::{Drive, Kinematics, Motion};
use crate::geometry::Geometry;
use crate::hand::HandModel;
use crate::parry_convert;
use crate::robot::{PairTables, Robot};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// Thickest slab an element is cut into for the balls that hold it (metres): two or three
/// balls per arm link. Thinner slabs (0.03–0.08 m) bound tighter but cost more than they save
/// (BENCHMARKS.md, "Cheaper probes").
const SLAB: f64 = 0.12;

/// Which margin a link's shapes get.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Group {
    /// Arm links (`arm_margin`).
    Arm,
    /// Hand and finger links (`hand_margin`).
    Hand,
}

/// One collision element of the robot, prepared for checking.
#[derive(Debug, Clone)]
pub(super) struct Body {
    pub(super) link: usize,
    pub(super) group: Group,
    /// The element as the URDF (or the hand model) gives it, before any margin.
    pub(super) geometry: Geometry,
    /// Pose of the parry shape in the link frame.
    pub(super) local: Pose,
    /// Grown by the group's margin, for tests against the world and a held object.
    pub(super) world_shape: SharedShape,
    /// Grown by half the self margin, for tests between links.
    pub(super) self_shape: SharedShape,
    /// Half the capsule's segment (0 for other shapes), and the radii of balls around the
    /// segment that hold the shape itself, the shape grown by the group's margin and the
    /// shape grown by half the self margin.
    pub(super) half_segment: f64,
    pub(super) core_radius: f64,
    pub(super) world_radius: f64,
    pub(super) self_radius: f64,
    /// Balls (in the frame of `local`) whose union holds the element grown by the group's
    /// margin, and by half the self margin ([`super::spheres`]).
    pub(super) world_spheres: Spheres,
    pub(super) self_spheres: Spheres,
    /// Balls inside the element grown by the group's margin ([`super::inside`]): where one
    /// reaches an object, the pair collides.
    pub(super) world_inside: Spheres,
}

/// A joint that moves a collision element when the arm moves: the link it turns or slides,
/// the arm joint that drives it and by how much, and its axis in the link frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Mover {
    pub(super) link: usize,
    pub(super) index: usize,
    pub(super) scale: f64,
    /// `None` for a prismatic joint.
    pub(super) axis: Option<Vector3<f64>>,
}

/// A collision model's self-collision tables ([`RobotCollision::table_summary`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct TableSummary {
    /// Link pairs with a table.
    pub tables: usize,
    /// Nodes over all tables.
    pub nodes: usize,
    /// Tables whose values were read from the robot's `self_tables.bin`.
    pub stored: usize,
}

/// The robot's collision model: its shapes, the link pairs to test and the joint chains used
/// to bound how far they move along edges.
#[derive(Debug, Clone)]
pub struct RobotCollision {
    pub(super) bodies: Vec<Body>,
    pub(super) self_pairs: Vec<(usize, usize)>,
    pub(super) mount_links: Vec<usize>,
    pub(super) margins: Margins,
    pub(super) tcp: usize,
    /// Where each chain's motion bounds start in a [`Sweep`]'s `bounds`: the elements of one
    /// link share the slots of its first element's chain.
    pub(super) offsets: Vec<usize>,
    /// The chains in groups of four, for bounding their motion side by side (one chain for
    /// the elements of one link).
    pub(super) lanes: ChainLanes,
    /// For the first element of a link that has several: the ball (its centre in the link's
    /// frame, its radius) that holds every element of the link, about which their shared
    /// chain's motion is bounded. One bound for a finger's five elements takes a third of the
    /// lanes away for 1.3 % more proof checks (BENCHMARKS.md, "Edges proved from the middle").
    pub(super) link_balls: Vec<Option<(Vector3<f64>, f64)>>,
    /// For each self pair, how many leading joints of their chains the two bodies share.
    pub(super) self_shared: Vec<usize>,
    /// For each self pair, its distance table if one or two joints move the two apart.
    pub(super) tables: PairTables,
    /// For each body, how many leading joints its chain shares with the TCP's.
    pub(super) tcp_shared: Vec<usize>,
    /// The links turned by arm-driven revolute joints, with their axes in the link frame.
    pub(super) turned: Vec<(usize, Vector3<f64>)>,
}

/// Every collision element of `robot` as (link, geometry, pose in the link frame): the URDF's
/// shapes, and the simulated hand's palm and pads ([`crate::hand`]), whose box corners reach
/// past the link's own shapes: the planner keeps clear whatever the simulated hand can touch.
pub(super) fn collision_elements(robot: &Robot) -> Vec<(usize, Geometry, Pose)> {
    let urdf = robot.links().iter().enumerate().flat_map(|(i, link)| {
        link.shapes
            .iter()
            .map(move |s| (i, s.geometry.clone(), s.origin))
    });
    let hand = HandModel::new(robot).map(|h| h.boxes()).unwrap_or_default();
    urdf.chain(hand).collect()
}

/// The balls of a robot's collision elements before any margin, in the order of
/// [`collision_elements`]: made once per robot ([`Robot::element_balls`]), as finding the
/// balls inside the hulls costs more than the rest of a model.
#[derive(Debug, Clone)]
pub(crate) struct ElementBalls {
    /// Balls that hold each element ([`Spheres::of_geometry`]).
    holding: Vec<Spheres>,
    /// Balls inside each element ([`inside`]).
    inside: Vec<Spheres>,
}

impl ElementBalls {
    /// The balls of `elements` (link, geometry, pose in the link frame).
    fn of(elements: &[(usize, Geometry, Pose)]) -> ElementBalls {
        ElementBalls {
            holding: elements
                .iter()
                .map(|(_, g, _)| Spheres::of_geometry(g, SLAB))
                .collect(),
            inside: elements.iter().map(|(_, g, _)| inside(g)).collect(),
        }
    }
}

/// The clearances kept (metres).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Margins {
    /// Arm links against the world.
    pub arm: f64,
    /// Hand links against the world.
    pub hand: f64,
    /// A held object against the world (against the arm, the larger of this and `hand`).
    pub held: f64,
    /// Between links.
    pub self_: f64,
}

impl Margins {
    /// The clearance kept between the world and links of `group`.
    pub(crate) fn world(&self, group: Group) -> f64 {
        match group {
            Group::Arm => self.arm,
            Group::Hand => self.hand,
        }
    }
}

/// The arm-driven joints between the base and `link`, base first.
pub(super) fn chain_to(kin: &Kinematics, link: usize) -> Vec<Mover> {
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
pub(super) fn shared(a: &[Mover], b: &[Mover]) -> usize {
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
        let elements = collision_elements(robot);
        let balls = robot.element_balls(|| ElementBalls::of(&elements));
        for ((i, geometry, origin), (spheres, within)) in elements
            .into_iter()
            .zip(balls.holding.iter().zip(&balls.inside))
        {
            let group = if robot.hand_links().contains(&i) {
                Group::Hand
            } else {
                Group::Arm
            };
            let margin = margins.world(group);
            let (world_shape, fix) = parry_convert::robot_shape(&geometry, margin);
            let (self_shape, _) = parry_convert::robot_shape(&geometry, 0.5 * margins.self_);
            // A grown hull is culled by the capsule that holds it.
            let (half_segment, core) = match &geometry {
                Geometry::Capsule { radius, length } => (0.5 * length, *radius),
                Geometry::RoundHull(hull) => (hull.half_length, hull.radius),
                other => (0.0, other.bounding_radius()),
            };
            bodies.push(Body {
                link: i,
                group,
                geometry: geometry.clone(),
                local: origin * fix,
                world_shape,
                self_shape,
                half_segment,
                core_radius: core,
                world_radius: core + margin,
                self_radius: core + 0.5 * margins.self_,
                world_spheres: spheres.grown(margin),
                self_spheres: spheres.grown(0.5 * margins.self_),
                world_inside: within.grown(margin),
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
        // The elements of one link share its first element's chain, bounded about the ball
        // that holds them all.
        let first_on_link: Vec<usize> = (0..chains.len())
            .map(|k| match bodies.get(k) {
                Some(b) => bodies.iter().position(|o| o.link == b.link).unwrap_or(k),
                None => k,
            })
            .collect();
        let mut offsets = Vec::with_capacity(chains.len() + 1);
        let mut next = 0;
        for (k, chain) in chains.iter().enumerate() {
            if first_on_link[k] == k {
                offsets.push(next);
                next += chain.len() + 1;
            } else {
                offsets.push(offsets[first_on_link[k]]);
            }
        }
        offsets.push(next);
        let link_balls = (0..bodies.len())
            .map(|k| {
                let on_link: Vec<&Body> = (0..bodies.len())
                    .filter(|&j| first_on_link[j] == k)
                    .map(|j| &bodies[j])
                    .collect();
                (on_link.len() > 1).then(|| {
                    let centre = on_link
                        .iter()
                        .map(|b| b.local.translation.vector)
                        .sum::<Vector3<f64>>()
                        / on_link.len() as f64;
                    let radius = on_link
                        .iter()
                        .map(|b| {
                            (b.local.translation.vector - centre).norm()
                                + b.half_segment
                                + b.core_radius
                        })
                        .fold(0.0, f64::max);
                    (centre, radius)
                })
            })
            .collect();
        let bounded: Vec<bool> = (0..chains.len()).map(|k| first_on_link[k] == k).collect();
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
        let tables = robot.pair_tables(margins.self_, || {
            self_pairs
                .iter()
                .zip(&self_shared)
                .map(|(&(i, j), &s)| {
                    let beyond = [&chains[i][s..], &chains[j][s..]];
                    let (a, b) = (&bodies[i], &bodies[j]);
                    let mut table = PairTable::for_pair(robot, a, b, beyond, 0.5 * margins.self_)?;
                    let stored = robot.stored_tables();
                    if !stored.is_empty() {
                        if let Some(values) = stored.get(&table.fingerprint(robot, a, b)) {
                            table.take_values(values);
                        }
                    }
                    Some(table)
                })
                .collect()
        });
        RobotCollision {
            bodies,
            self_pairs,
            mount_links: robot.mount_links().to_vec(),
            margins,
            tcp,
            lanes: ChainLanes::of(&chains, &bounded),
            offsets,
            link_balls,
            self_shared,
            tables,
            tcp_shared,
            turned,
        }
    }

    /// The self-collision tables and how many of their nodes there are, and how many tables
    /// took stored values when they were made.
    pub fn table_summary(&self) -> TableSummary {
        let tables: Vec<&PairTable> = self.tables.iter().flatten().collect();
        TableSummary {
            tables: tables.len(),
            nodes: tables.iter().map(|t| t.len()).sum(),
            stored: tables.iter().filter(|t| t.stored()).count(),
        }
    }

    /// Computes every node of every self-collision table not known yet, on `threads`
    /// threads, and returns them all for a file (`akl robot tables`).
    pub fn fill_tables(&self, robot: &Robot, threads: usize) -> StoredTables {
        let mut stored = StoredTables::default();
        for (table, &(i, j)) in self.tables.iter().zip(&self.self_pairs) {
            let Some(table) = table else { continue };
            let (a, b) = (&self.bodies[i], &self.bodies[j]);
            table.fill(robot, a, b, threads);
            let values = table.values().expect("every node was just computed");
            stored.push(table.fingerprint(robot, a, b), values);
        }
        stored
    }

    /// What the contact rules need to know of `body`'s link.
    pub(super) fn role(&self, body: &Body) -> LinkRole {
        LinkRole {
            hand: body.group == Group::Hand,
            mount: self.mount_links.contains(&body.link),
        }
    }

    /// The margins in use.
    pub fn margins(&self) -> Margins {
        self.margins
    }

    /// Number of link pairs tested against each other.
    #[cfg(test)]
    pub(crate) fn self_pair_count(&self) -> usize {
        self.self_pairs.len()
    }
}
