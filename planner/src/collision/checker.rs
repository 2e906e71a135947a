//! The checker: one configuration, or a joint-space edge, against the world and the arm
//! itself.

use super::cull::{
    bounding_box, box_gap_sq, placed, segment_distance_sq, set_lanes, Placed, BOX_LANES,
};
use super::held::Held;
use super::hit::Hit;
use super::lanes::Element;
use super::model::{Body, Group, RobotCollision};
use super::pair_table::Tabled;
use super::scene::{Obstacle, Scene};
use super::spheres::{gap_between, Placement};
use super::sweep::{Motion, Proof, Sweep};
use crate::contact_rules::Allowances;
use crate::parry_convert::Slab;
use crate::robot::Robot;
use crate::{contact_rules, parry_convert};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;
use smallvec::SmallVec;
use std::cell::Cell;
use std::collections::VecDeque;

/// Links whose poses a check keeps on the stack; robots with more spill to the heap.
const INLINE_LINKS: usize = 32;

/// Collision elements whose placements a check keeps on the stack; more spill to the heap.
const INLINE_BODIES: usize = 64;

/// Link poses of one configuration.
pub(super) type LinkPoses = SmallVec<[Pose; INLINE_LINKS]>;

/// Placed collision elements of one configuration.
pub(super) type PlacedBodies = SmallVec<[Placed; INLINE_BODIES]>;

/// What parry's distances are trusted to (metres): clearances it reports are reduced by
/// this much before they are relied on (the checker's and the wrist tables').
pub(super) const DISTANCE_TOLERANCE: f64 = 1e-5;

/// Checks configurations of one robot in one scene.
#[derive(Debug, Clone)]
pub struct Checker<'a> {
    pub(super) robot: &'a Robot,
    pub(super) model: &'a RobotCollision,
    pub(super) scene: &'a Scene,
    /// Counts every configuration probed, when set ([`Checker::counting`]).
    probes: Option<&'a Cell<u64>>,
}

impl<'a> Checker<'a> {
    /// A checker for `robot` (with its prepared `model`) in `scene`.
    pub fn new(robot: &'a Robot, model: &'a RobotCollision, scene: &'a Scene) -> Self {
        Checker {
            robot,
            model,
            scene,
            probes: None,
        }
    }

    /// The same checker, adding one to `probes` for every configuration it probes: a measure
    /// of a plan's collision-checking work that, unlike its time, is the same on any machine.
    pub(crate) fn counting(self, probes: &'a Cell<u64>) -> Self {
        Checker {
            probes: Some(probes),
            ..self
        }
    }

    /// Adds one to the probes counted, if they are ([`Checker::counting`]).
    fn count_probe(&self) {
        if let Some(probes) = self.probes {
            probes.set(probes.get() + 1);
        }
    }

    /// The robot.
    pub fn robot(&self) -> &'a Robot {
        self.robot
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

    pub(super) fn within_limits(&self, q: &[f64]) -> bool {
        q.iter()
            .zip(self.robot.joint_limits())
            .all(|(v, [lo, hi])| *v >= *lo && *v <= *hi)
    }

    /// Whether `q` is collision-free (see [`Checker::check`]).
    pub fn is_free(&self, q: &[f64], width: f64, held: Option<&Held>, allow: &Allowances) -> bool {
        self.check(q, width, held, allow).is_none()
    }

    /// Writes into `sweep.bounds` the motion bounds of every chain for the joint motion
    /// `sweep.step` (either way) about the configuration whose link poses are `poses`, and
    /// into `sweep.carried` each chain's first-order motion as vectors.
    ///
    /// Each slot takes the smaller, over the whole stretch, of two bounds (module
    /// documentation): the sum over the joints of each one's turn times the element's reach
    /// from its axis, and the element's velocity at the check (the joints' motions added as
    /// vectors, so that turns that carry it opposite ways cancel) plus what that velocity can
    /// change along the stretch.
    pub(super) fn sweep_bounds(
        &self,
        poses: &[Pose],
        placed_bodies: &[Placed],
        held: Option<&Held>,
        sweep: &mut Sweep,
    ) {
        let model = self.model;
        let tcp = poses[model.tcp];
        let mut axes: SmallVec<[Vector3<f64>; INLINE_LINKS]> =
            SmallVec::from_elem(Vector3::zeros(), poses.len());
        for &(link, axis) in &model.turned {
            axes[link] = poses[link].rotation * axis;
        }
        let element = |k: usize| match (placed_bodies.get(k), model.bodies.get(k)) {
            (Some(p), Some(b)) => match model.link_balls[k] {
                Some((centre, radius)) => Element {
                    centre: poses[b.link].transform_point(&centre.into()).coords,
                    extent: radius,
                },
                None => Element {
                    centre: p.pose.translation.vector,
                    extent: b.half_segment + b.core_radius,
                },
            },
            _ => match held {
                Some(h) => Element {
                    centre: (tcp * h.in_tcp).translation.vector,
                    extent: h.core,
                },
                None => Element {
                    centre: tcp.translation.vector,
                    extent: 0.0,
                },
            },
        };
        model
            .lanes
            .bound(sweep, &axes, poses, element, &model.offsets);
    }

    /// Upper bound on how far any point of the robot's collision elements, or of `held`,
    /// moves when the arm goes in a straight joint-space line from `a` to `b` with gripper
    /// opening `width` (the bound of [`Checker::edge`], taken about the edge's midpoint).
    #[cfg(test)]
    pub(crate) fn sweep_bound(&self, a: &[f64], b: &[f64], width: f64, held: Option<&Held>) -> f64 {
        let mid: Vec<f64> = a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect();
        let mut poses = LinkPoses::from_elem(Pose::identity(), self.robot.links().len());
        self.robot
            .kinematics()
            .link_poses_into(&mid, width, &mut poses);
        let placed_bodies: PlacedBodies = self
            .model
            .bodies
            .iter()
            .map(|body| placed(body, &poses[body.link]))
            .collect();
        let mut sweep = Sweep::new(self.model, a.len());
        for (s, (x, y)) in sweep.step.iter_mut().zip(a.iter().zip(b)) {
            *s = 0.5 * (y - x);
        }
        self.sweep_bounds(&poses, &placed_bodies, held, &mut sweep);
        let last = self.model.offsets.len() - if held.is_some() { 1 } else { 2 };
        (0..last)
            .map(|k| sweep.bounds[self.model.offsets[k]].whole())
            .fold(0.0, f64::max)
            * 2.0
    }

    /// The world poses of the links at `q` with gripper opening `width`, and of the collision
    /// elements on them.
    pub(super) fn placements(&self, q: &[f64], width: f64) -> (LinkPoses, PlacedBodies) {
        let mut poses = LinkPoses::new();
        let mut placed_bodies = PlacedBodies::new();
        self.place_into(q, width, &mut poses, &mut placed_bodies);
        (poses, placed_bodies)
    }

    /// [`Checker::placements`] written into empty buffers: a check fills its own on the
    /// stack instead of moving a few kilobytes of returned buffers (4 % of a check).
    #[inline(always)]
    fn place_into(
        &self,
        q: &[f64],
        width: f64,
        poses: &mut LinkPoses,
        placed_bodies: &mut PlacedBodies,
    ) {
        poses.resize(self.robot.links().len(), Pose::identity());
        self.robot
            .kinematics()
            .link_poses_at(&self.scene.base, q, width, poses);
        placed_bodies.extend(self.model.bodies.iter().map(|b| placed(b, &poses[b.link])));
    }

    /// The first collision of `q` (within the joint limits), or, when `PROVE` is set and
    /// `sweep` holds the joint motion of a stretch about `q`, the fraction of that stretch
    /// proved free (see the module documentation). Plain checks are compiled without the
    /// proof's work.
    pub(super) fn probe<const PROVE: bool>(
        &self,
        q: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
        sweep: Option<&mut Sweep>,
    ) -> Result<f64, Hit> {
        self.count_probe();
        let links = self.robot.links();
        let mut poses = LinkPoses::new();
        let mut placed_bodies = PlacedBodies::new();
        self.place_into(q, width, &mut poses, &mut placed_bodies);
        let model = self.model;
        let bodies = &model.bodies;
        let placed_bodies = &placed_bodies[..];
        let mut proof = sweep.filter(|_| PROVE).map(|s| {
            self.sweep_bounds(&poses, placed_bodies, held, s);
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
            let tabled = match model.tables[p].as_ref() {
                None => f64::MIN,
                Some(t) => match t.lookup(self.robot, ba, bb, q) {
                    Tabled::Apart(gap) => gap,
                    Tabled::Overlapping => {
                        return Err(Hit::SelfCollision(
                            links[ba.link].name.clone(),
                            links[bb.link].name.clone(),
                        ))
                    }
                },
            };
            let reach = ba.self_radius + bb.self_radius;
            let balls = reach + ba.half_segment + bb.half_segment;
            let centres = 0.5 * ((pa.a + pa.b) - (pb.a + pb.b));
            let moved = proof.as_ref().map_or(Motion::default(), |pr| {
                let s = model.self_shared[p];
                pr.moved(i, s) + pr.moved(j, s)
            });
            let centres_sq = centres.norm_squared();
            if let Some(pr) = proof.as_mut() {
                // The table first, then the distance of the bounding balls, the segments'
                // only if it matters, then the balls that hold the two elements.
                if tabled > 0.0 && pr.settled(moved, self_slack + tabled) {
                    continue;
                }
                // A full table bounds the pair over the whole stretch at once (asked where
                // it puts the pair apart here: elsewhere its blocks seldom clear it).
                if let Some(t) = model.tables[p].as_ref().filter(|_| tabled > 0.0) {
                    let stretch = (&pr.sweep.step[..], pr.fraction);
                    if t.clear_over(self.robot, q, stretch, -self_slack) {
                        continue;
                    }
                }
                if centres_sq > balls * balls
                    && pr.settled_sq(moved, self_slack - balls, centres_sq)
                {
                    continue;
                }
                let gap = segment_distance_sq(&pa.a, &pa.b, &pb.a, &pb.b).sqrt() - reach;
                if gap > 0.0 && pr.settled(moved, self_slack + gap) {
                    continue;
                }
                let gap = gap.max(self_gap(ba, pa, bb, pb)).max(tabled);
                if gap > 0.0 {
                    pr.limit(moved, self_slack + gap);
                    continue;
                }
            } else if tabled > 0.0
                || centres_sq > balls * balls
                || segment_distance_sq(&pa.a, &pa.b, &pb.a, &pb.b) > reach * reach
                || self_gap(ba, pa, bb, pb) > 0.0
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
        // Robot against the world: bounding boxes, then the balls that hold each element,
        // then parry. Where a ball reaches an object the exact test comes at once; where the
        // balls keep clear but could still shorten the stretch, the exact distance is left
        // for the end (`nearest`), when the other clearances may already have settled it.
        let mut nearest: SmallVec<[Near; 16]> = SmallVec::new();
        for (k, (b, p)) in bodies.iter().zip(placed_bodies).enumerate() {
            let slack = 0.5 * m.world(b.group);
            let moved = proof
                .as_ref()
                .map_or(Motion::default(), |pr| pr.moved(k, 0));
            let bounds = bounding_box(p, b.world_radius);
            let role = model.role(b);
            let mut place: Option<Placement> = None;
            let scene = self.scene;
            // Boxes apart: nothing to test, and for a proof nothing to measure where the
            // boxes' gap settles the stretch (four objects at a time; the fraction proved may
            // shrink on the way, settling more, so each is asked again).
            for (group, lanes) in scene.boxes.iter().enumerate() {
                // A plain check looks only at the boxes that meet, and uses no gap.
                let (todo, gaps) = match proof.as_ref() {
                    Some(pr) => lanes.within(&bounds, pr.useful_clearance(moved, slack)),
                    None => (lanes.meeting(&bounds), [0.0; BOX_LANES]),
                };
                for lane in set_lanes(todo) {
                    let index = group * BOX_LANES + lane;
                    let (o, gap_sq) = (&scene.obstacles[index], gaps[lane]);
                    if gap_sq > 0.0
                        && proof
                            .as_ref()
                            .is_some_and(|pr| pr.settled_sq(moved, slack, gap_sq))
                    {
                        continue;
                    }
                    if contact_rules::link_may_touch(role, &o.name, None, scene.mount(), allow) {
                        continue;
                    }
                    let Some(pr) = proof.as_mut() else {
                        let at = place.get_or_insert_with(|| Placement::of(&p.pose));
                        if o.target.gap(&b.world_spheres, at) > 0.0
                            || !(o.target.reaches(&b.world_inside, at)
                                || parry_convert::intersects(
                                    &b.world_shape,
                                    &p.pose,
                                    &o.shape,
                                    &o.pose,
                                ))
                        {
                            continue;
                        }
                        return Err(Hit::World(links[b.link].name.clone(), o.name.clone()));
                    };
                    let at = place.get_or_insert_with(|| Placement::of(&p.pose));
                    let gap = o.target.gap(&b.world_spheres, at).max(gap_sq.sqrt());
                    if gap > 0.0 {
                        if !pr.settled(moved, slack + gap) {
                            // Motion across a face of a box may prove more.
                            let across = o
                                .target
                                .face(&b.world_spheres, at)
                                .map_or(0.0, |face| pr.share_across(k, slack, &face));
                            let share = moved.share_within(slack + gap).max(across);
                            if share < pr.fraction {
                                nearest.push(Near {
                                    body: k,
                                    obstacle: index,
                                    moved,
                                    slack,
                                    gap,
                                    share,
                                });
                            }
                        }
                        continue;
                    }
                    if o.target.reaches(&b.world_inside, at)
                        || !clear_of(&b.world_shape, p, &bounds, o, Some(pr), (k, moved), slack)
                    {
                        return Err(Hit::World(links[b.link].name.clone(), o.name.clone()));
                    }
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
            let moved = proof
                .as_ref()
                .map_or(Motion::default(), |pr| pr.moved(held_chain, 0));
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
                // A movable object is only where it was perceived: keep the larger margin.
                let (shape, margin) = if o.movable {
                    (&h.near_arm, h.arm_margin)
                } else {
                    (&h.grown, h.margin)
                };
                let slack = 0.5 * margin;
                let mover = (held_chain, moved);
                if !clear_of(shape, &ball, &bounds, o, proof.as_mut(), mover, slack) {
                    return Err(Hit::HeldWorld(h.name.clone(), o.name.clone()));
                }
            }
            let slack = 0.5 * (h.arm_margin + 0.5 * m.self_);
            let arm_extent = h.core + h.arm_margin;
            for (k, (b, p)) in bodies.iter().zip(placed_bodies).enumerate() {
                if b.group == Group::Hand {
                    continue;
                }
                let reach = arm_extent + b.self_radius;
                let moved = proof.as_ref().map_or(Motion::default(), |pr| {
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
                if parry_convert::intersects(&b.self_shape, &p.pose, &h.near_arm, &pose) {
                    return Err(Hit::HeldRobot(h.name.clone(), links[b.link].name.clone()));
                }
                if let Some(pr) = proof.as_mut() {
                    pr.limit(moved, slack);
                }
            }
        }
        if let Some(pr) = proof.as_mut() {
            // The least promising first: once one is settled by its bound, so are the rest.
            // Picked one at a time rather than sorted: the loop ends at the first settled
            // pair, and the pairs after it need no order.
            while let Some(at) =
                (0..nearest.len()).min_by(|&x, &y| nearest[x].share.total_cmp(&nearest[y].share))
            {
                let n = nearest.swap_remove(at);
                if n.share >= pr.fraction {
                    break;
                }
                let (b, p, o) = (
                    &bodies[n.body],
                    &placed_bodies[n.body],
                    &self.scene.obstacles[n.obstacle],
                );
                // The exact slab across a face of a box, before an exact distance.
                let face = face_slab(&b.world_shape, p, o)
                    .map_or(0.0, |face| pr.share_across(n.body, n.slack, &face));
                if face >= pr.fraction {
                    continue;
                }
                let n = Near {
                    share: n.share.max(face),
                    ..n
                };
                // Beyond this distance the pair shortens nothing: GJK may stop there.
                let reach = pr.useful_clearance(n.moved, n.slack) + DISTANCE_TOLERANCE;
                let separation = parry_convert::separation_up_to(
                    &b.world_shape,
                    &p.pose,
                    &o.shape,
                    &o.pose,
                    reach,
                );
                let exact = separation.map_or(0.0, |s| s.distance - DISTANCE_TOLERANCE);
                let across = separation.and_then(|s| s.slab).map(|slab| Slab {
                    width: exact,
                    ..slab
                });
                let distance = exact.max(n.gap);
                pr.limit_by_clearance(n.body, n.moved, n.slack, distance, across, n.share);
            }
        }
        Ok(proof.map_or(1.0, |pr| pr.fraction))
    }

    /// The first collision on the straight joint-space edge from `a` to `b` (endpoints
    /// included), or `None` if every clearance keeps at least half its margin all along it
    /// and its whole margin at both ends.
    ///
    /// Both ends get a plain check; then the edge is proved free from its middle (see
    /// [`Checker::screened_edge`]).
    pub(crate) fn edge(
        &self,
        a: &[f64],
        b: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
    ) -> Option<Hit> {
        if !self.within_limits(a) {
            return Some(Hit::Limits);
        }
        if let Err(hit) = self.probe::<false>(a, width, held, allow, None) {
            return Some(hit);
        }
        self.screened_edge(a, b, width, held, allow, 0)
    }

    /// [`Checker::edge`] for an edge whose start `a` is already known to pass a plain check
    /// (a node of a search tree), after a screen of `points` points of the edge
    /// ([`Checker::screen`]): a collision found there rejects the edge before any proof.
    ///
    /// The end `b` gets a plain check. Then each check on the edge proves a stretch about it
    /// free: no point moves further than the clearance found there plus half its margin, by
    /// the bound of [`Checker::sweep_bound`] taken at the check for the stretch (see the
    /// module documentation). The first check is at the midpoint, for half the edge either
    /// way; then the midpoint of each part left on either side of what a check proved, and so
    /// on breadth first, so that checks spread over the edge in bisection order and
    /// collisions are found early. The ends are proved by the checks nearest them rather
    /// than from themselves: a check at an end proves a stretch on one side only, for a bound
    /// taken over the whole edge, and such checks cost a search about 15 % more time
    /// (BENCHMARKS.md, "Edges proved from the middle"). Each check proves at least half the
    /// smallest margin of motion, so the number of checks is at most about the bound on how
    /// far points move divided by that.
    pub(crate) fn screened_edge(
        &self,
        a: &[f64],
        b: &[f64],
        width: f64,
        held: Option<&Held>,
        allow: &Allowances,
        points: usize,
    ) -> Option<Hit> {
        if !self.within_limits(a) || !self.within_limits(b) {
            return Some(Hit::Limits);
        }
        if let Some(hit) = self.screen(a, b, width, allow, points) {
            return Some(hit);
        }
        if let Err(hit) = self.probe::<false>(b, width, held, allow, None) {
            return Some(hit);
        }
        let mut sweep = Sweep::new(self.model, a.len());
        let mut open = VecDeque::from([(0.0, 1.0)]);
        let mut q = vec![0.0; a.len()];
        while let Some((lo, hi)) = open.pop_front() {
            let mid = 0.5 * (lo + hi);
            let half = 0.5 * (hi - lo);
            for i in 0..a.len() {
                q[i] = a[i] + mid * (b[i] - a[i]);
                sweep.step[i] = half * (b[i] - a[i]);
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

    /// A collision of the elements `placed_bodies` with the world that balls inside them make
    /// certain, if there is one, without any exact test. The elements are taken from the
    /// hand back to the base: the far end of the arm sweeps the most space and collides most.
    fn certain_world_hit(&self, placed_bodies: &[Placed], allow: &Allowances) -> Option<Hit> {
        let scene = self.scene;
        for (b, p) in self.model.bodies.iter().zip(placed_bodies).rev() {
            let bounds = bounding_box(p, b.world_radius);
            let role = self.model.role(b);
            let mut place: Option<Placement> = None;
            for (group, lanes) in scene.boxes.iter().enumerate() {
                for lane in set_lanes(lanes.meeting(&bounds)) {
                    let o = &scene.obstacles[group * BOX_LANES + lane];
                    let at = place.get_or_insert_with(|| Placement::of(&p.pose));
                    if o.target.reaches(&b.world_inside, at)
                        && !contact_rules::link_may_touch(role, &o.name, None, scene.mount(), allow)
                    {
                        return Some(Hit::World(
                            self.robot.links()[b.link].name.clone(),
                            o.name.clone(),
                        ));
                    }
                }
            }
        }
        None
    }

    /// A collision of the arm with the world that balls inside its elements make certain
    /// ([`Checker::certain_world_hit`]) at one of the first `points` points of the edge from
    /// `a` to `b` in bisection order from `b` (1, 1/2, 1/4, 3/4, 1/8, ...), but for the first,
    /// `b` itself, which the edge's plain check of `b` after the screen covers (one placement
    /// of the arm there, not two: the searches' instructions −2.6 %). A proof's checks
    /// measure clearances and stop only where one is negative; a blocked edge usually shows
    /// such a collision at one of these points, found for the price of placing the arm. The
    /// screen looks for nothing else (not the held object, not the arm against itself, no
    /// exact test): what it misses the proof finds, and a full plain check at a point the
    /// proof then measures again cost three times as much (BENCHMARKS.md, "A screen of
    /// certain collisions"). Both ends must be within the joint limits
    /// ([`Checker::screened_edge`] checks them).
    pub(super) fn screen(
        &self,
        a: &[f64],
        b: &[f64],
        width: f64,
        allow: &Allowances,
        points: usize,
    ) -> Option<Hit> {
        let mut q = vec![0.0; a.len()];
        for k in 1..points {
            let t = bisection_point(k);
            for (v, (x, y)) in q.iter_mut().zip(a.iter().zip(b)) {
                *v = x + t * (y - x);
            }
            // Within the joint limits: the ends are, and the limits are a box.
            self.count_probe();
            let mut poses = LinkPoses::new();
            let mut placed_bodies = PlacedBodies::new();
            self.place_into(&q, width, &mut poses, &mut placed_bodies);
            if let Some(hit) = self.certain_world_hit(&placed_bodies, allow) {
                return Some(hit);
            }
        }
        None
    }
}

/// The `k`-th point of a unit interval in bisection order: 1, then 1/2, 1/4, 3/4, 1/8,
/// 3/8, 5/8, 7/8, 1/16, ...
fn bisection_point(k: usize) -> f64 {
    if k == 0 {
        return 1.0;
    }
    let level = k.ilog2();
    let odd = 2 * (k - (1 << level)) + 1;
    odd as f64 / f64::from(1u32 << (level + 1))
}

/// A clearance between an element and an object that its balls bound from below by `gap`,
/// whose exact distance may prove less of the stretch than the other clearances.
struct Near {
    body: usize,
    obstacle: usize,
    moved: Motion,
    slack: f64,
    gap: f64,
    /// The share of the stretch that `gap`, or a slab across a face of the object, proves.
    share: f64,
}

/// A lower bound on the distance between two elements grown by half the self margin, from
/// their balls.
fn self_gap(a: &Body, pa: &Placed, b: &Body, pb: &Placed) -> f64 {
    gap_between(
        &a.self_spheres,
        &Placement::of(&pa.pose),
        &b.self_spheres,
        &Placement::of(&pb.pose),
    )
}

/// The widest slab across a face of `o`, a box, between it and `shape` at `placed.pose`
/// ([`parry_convert::box_face_slab`]), its width less what distances are trusted to.
fn face_slab(shape: &SharedShape, placed: &Placed, o: &Obstacle) -> Option<Slab> {
    parry_convert::box_face_slab(shape, &placed.pose, &o.shape, &o.pose).map(|face| Slab {
        width: face.width - DISTANCE_TOLERANCE,
        ..face
    })
}

/// Whether `shape` at `placed.pose` (inside the world-axis-aligned box `bounds`) is
/// clear of `o`; with a proof, for the element of chain `mover.0` moving up to `mover.1` with
/// `slack` to spare, the clearance found also limits the fraction proved free (by the motion
/// along the direction the exact distance separates them in, where that proves more).
#[inline(always)]
pub(super) fn clear_of(
    shape: &SharedShape,
    placed: &Placed,
    bounds: &[Vector3<f64>; 2],
    o: &Obstacle,
    proof: Option<&mut Proof>,
    (chain, moved): (usize, Motion),
    slack: f64,
) -> bool {
    let Some(pr) = proof else {
        let overlap =
            (0..3).all(|i| bounds[0][i] <= o.target.max[i] && bounds[1][i] >= o.target.min[i]);
        return !overlap || !parry_convert::intersects(shape, &placed.pose, &o.shape, &o.pose);
    };
    let gap_sq = box_gap_sq(bounds, &o.target.min, &o.target.max);
    if gap_sq > 0.0 {
        pr.limit(moved, slack + gap_sq.sqrt());
        return true;
    }
    if pr.settled(moved, slack) {
        return !parry_convert::intersects(shape, &placed.pose, &o.shape, &o.pose);
    }
    // A face of a box that keeps the shapes apart may settle the pair without a distance.
    let face = face_slab(shape, placed, o)
        .filter(|face| face.width > 0.0)
        .map_or(0.0, |face| pr.share_across(chain, slack, &face));
    if face >= pr.fraction {
        return true;
    }
    let reach = pr.useful_clearance(moved, slack) + DISTANCE_TOLERANCE;
    match parry_convert::separation_up_to(shape, &placed.pose, &o.shape, &o.pose, reach) {
        Some(s) if s.distance > 0.0 => {
            let exact = (s.distance - DISTANCE_TOLERANCE).max(0.0);
            let across = s.slab.map(|slab| Slab {
                width: exact,
                ..slab
            });
            pr.limit_by_clearance(chain, moved, slack, exact, across, face);
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
mod bisection_tests {
    use super::bisection_point;

    #[test]
    fn points_come_in_bisection_order_from_the_far_end() {
        let points: Vec<f64> = (0..9).map(bisection_point).collect();
        assert_eq!(
            points,
            [1.0, 0.5, 0.25, 0.75, 0.125, 0.375, 0.625, 0.875, 0.0625]
        );
    }
}
