//! RRT-Connect (Kuffner & LaValle 2000) in joint space: two trees, one from the start and
//! one from every goal configuration, each extension greedily connecting the other tree.
//!
//! Two refinements, each an option: a dynamic domain (Yershova, Jaillet, Siméon and LaValle,
//! ICRA 2005), which stops sampling far from the nodes next to obstacles, so that a tree in
//! a narrow space is not pulled against its walls by samples it can never reach; and balanced
//! trees, which always grow the smaller one. A node from which extensions keep failing
//! takes shorter steps, so that a tree started in a pocket (a goal between a grasped can
//! and a shelf's wall) creeps out of it instead of trying one long step after another.
//! Edges are screened for certain collisions at a few points before they are proved free, as
//! many as the share of blocked edges so far makes worth it.

use crate::space::{distance, Space};
use rand::Rng;

/// Settings of RRT-Connect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RrtOptions {
    /// Largest joint-space step (Euclidean, radians) of one extension.
    pub range: f64,
    /// Samples drawn before giving up.
    pub max_iterations: usize,
    /// The dynamic domain, if used: a sample farther from its nearest node than the node's
    /// domain radius is drawn again (see [`DynamicDomain`]).
    pub dynamic_domain: Option<DynamicDomain>,
    /// Whether the smaller tree is always the one extended toward the sample (otherwise the
    /// trees take turns).
    pub balance: bool,
    /// Failed extensions toward samples from one node over which that node's step halves
    /// (smoothly, down to [`MIN_STEP`]); `None` keeps every step at `range`.
    pub halve_step_after: Option<u32>,
}

/// The shortest step a node's failures shrink it to (radians): short enough to creep along
/// a passage a few millimetres wide, long enough that a step moves the arm.
pub const MIN_STEP: f64 = 0.05;

/// The default of [`RrtOptions::halve_step_after`], chosen by measurement (BENCHMARKS.md,
/// "Steps that shrink in pockets"): fewer failures shrank the steps of nodes that only had
/// to wait for one long lucky step, more left tight pockets unsolved within the budget.
pub const HALVE_STEP_AFTER: u32 = 1000;

/// The dynamic domain's settings: a node whose extension hit an obstacle gets a finite
/// radius (`radius`, radians), which each success from it widens by a factor `1 + alpha` and
/// each failure narrows by `1 - alpha`, never below `min_radius`; other nodes' domains are
/// unbounded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicDomain {
    /// The radius a node's domain gets when an extension from it first fails.
    pub radius: f64,
    /// How much each later success widens, and each failure narrows, it.
    pub alpha: f64,
    /// The smallest radius.
    pub min_radius: f64,
}

impl Default for DynamicDomain {
    /// VAMP's settings for the Panda (radius 4, alpha 1e-4, at least 1).
    fn default() -> Self {
        DynamicDomain {
            radius: 4.0,
            alpha: 1e-4,
            min_radius: 1.0,
        }
    }
}

impl Default for RrtOptions {
    fn default() -> Self {
        RrtOptions {
            range: 1.0,
            max_iterations: 20_000,
            dynamic_domain: Some(DynamicDomain::default()),
            balance: true,
            halve_step_after: Some(HALVE_STEP_AFTER),
        }
    }
}

/// A tree stored flat: node i is `nodes[i*dof..(i+1)*dof]`, with its parent index.
struct Tree {
    dof: usize,
    nodes: Vec<f64>,
    parents: Vec<usize>,
    /// Index of the root each node descends from (the goal tree has several roots).
    roots: Vec<usize>,
    /// Each node's dynamic-domain radius (infinite until an extension from it fails).
    radii: Vec<f64>,
    /// How many extensions toward samples from each node failed.
    failures: Vec<u32>,
}

const NO_PARENT: usize = usize::MAX;

impl Tree {
    fn new(dof: usize) -> Tree {
        Tree {
            dof,
            nodes: Vec::new(),
            parents: Vec::new(),
            roots: Vec::new(),
            radii: Vec::new(),
            failures: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.parents.len()
    }

    fn node(&self, i: usize) -> &[f64] {
        &self.nodes[i * self.dof..(i + 1) * self.dof]
    }

    fn add(&mut self, q: &[f64], parent: usize) -> usize {
        let i = self.len();
        self.nodes.extend_from_slice(q);
        self.parents.push(parent);
        self.radii.push(f64::INFINITY);
        self.failures.push(0);
        self.roots.push(if parent == NO_PARENT {
            i
        } else {
            self.roots[parent]
        });
        i
    }

    /// The step of an extension from node `i`: `range`, halved for every `halve_after`
    /// failures from it so far (smoothly), but not below [`MIN_STEP`].
    fn step(&self, i: usize, range: f64, halve_after: Option<u32>) -> f64 {
        match halve_after {
            Some(n) if self.failures[i] > 0 => {
                let halvings = f64::from(self.failures[i]) / f64::from(n.max(1));
                (range * (-halvings).exp2()).max(MIN_STEP.min(range))
            }
            _ => range,
        }
    }

    /// The node nearest `q` (the first of equals), by a scan of the flat node array.
    fn nearest(&self, q: &[f64]) -> usize {
        let mut best = 0;
        let mut best_d = f64::INFINITY;
        for (i, node) in self.nodes.chunks_exact(self.dof).enumerate() {
            let d: f64 = node.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum();
            if d < best_d {
                best_d = d;
                best = i;
            }
        }
        best
    }

    /// Nodes from the root down to `i`.
    fn path_to(&self, mut i: usize) -> Vec<Vec<f64>> {
        let mut path = Vec::new();
        while i != NO_PARENT {
            path.push(self.node(i).to_vec());
            i = self.parents[i];
        }
        path.reverse();
        path
    }
}

/// How many points of an edge are screened before its proof (the end first, which the edge's
/// plain check of it covers), from how often the edges tried so far were blocked: screening
/// (see [`Space::screened_edge_valid`]) pays where most edges are blocked and is overhead
/// where most are free.
#[derive(Debug, Default)]
struct Screening {
    tried: u32,
    blocked: u32,
}

/// Screening points per radian of an edge's length when every edge is blocked, and at most.
/// Chosen, with screening starting once half the edges are blocked, by measurement
/// (BENCHMARKS.md, "Screening edges").
const SCREEN_PER_RADIAN: f64 = 8.0;
const SCREEN_MAX: usize = 8;

impl Screening {
    /// Points to screen on an edge `length` long: none while at most half the edges tried so
    /// far were blocked (a half to begin with), rising to `SCREEN_PER_RADIAN` per radian as
    /// all are; at most `SCREEN_MAX`.
    fn points(&self, length: f64) -> usize {
        let rate = (f64::from(self.blocked) + 0.5) / (f64::from(self.tried) + 1.0);
        Self::points_if_blocked(length, (2.0 * rate - 1.0).max(0.0))
    }

    /// Points to screen on an edge `length` long: `share` (0 to 1) of what it gets when every
    /// edge so far was blocked. The direct edge from the start to a goal gets the whole of
    /// it: a search is run because the way is not clear, and MotionBenchMaker's direct edges
    /// showed it (per-run time 0.89 to 0.98 of the unscreened edge's, round by round, with
    /// every search the same; BENCHMARKS.md, "A screen of certain collisions").
    fn points_if_blocked(length: f64, share: f64) -> usize {
        ((length * SCREEN_PER_RADIAN * share) as usize).min(SCREEN_MAX)
    }

    /// Whether the edge from `a` to `b` is free, screened as the record so far says, and
    /// adding it to the record.
    fn edge_valid(&mut self, space: &Space, a: &[f64], b: &[f64]) -> bool {
        let valid = space.screened_edge_valid(a, b, self.points(distance(a, b)));
        self.tried += 1;
        self.blocked += u32::from(!valid);
        valid
    }
}

enum Extend {
    Reached(usize),
    Advanced(usize),
    Trapped,
    /// The target lies outside the nearest node's dynamic domain: nothing was checked.
    Outside,
}

/// Extends `tree` one step of at most `range` towards `target`, within the nodes' dynamic
/// domains if `domain` is given (and updating them), the step shrinking with the node's
/// failures if `halve_after` is given (and counting them).
fn extend(
    tree: &mut Tree,
    target: &[f64],
    space: &Space,
    screening: &mut Screening,
    range: f64,
    domain: Option<&DynamicDomain>,
    halve_after: Option<u32>,
) -> Extend {
    let near = tree.nearest(target);
    let from = tree.node(near).to_vec();
    let d = distance(&from, target);
    if domain.is_some() && d > tree.radii[near] {
        return Extend::Outside;
    }
    let range = tree.step(near, range, halve_after);
    let (to, reached) = if d <= range {
        (target.to_vec(), true)
    } else {
        let t = range / d;
        (
            from.iter()
                .zip(target)
                .map(|(a, b)| a + t * (b - a))
                .collect(),
            false,
        )
    };
    if !screening.edge_valid(space, &from, &to) {
        if halve_after.is_some() {
            tree.failures[near] = tree.failures[near].saturating_add(1);
        }
        if let Some(dd) = domain {
            let r = &mut tree.radii[near];
            *r = if r.is_finite() {
                (*r * (1.0 - dd.alpha)).max(dd.min_radius)
            } else {
                dd.radius
            };
        }
        return Extend::Trapped;
    }
    if let Some(dd) = domain {
        let r = &mut tree.radii[near];
        if r.is_finite() {
            *r *= 1.0 + dd.alpha;
        }
    }
    let i = tree.add(&to, near);
    if reached {
        Extend::Reached(i)
    } else {
        Extend::Advanced(i)
    }
}

/// Extends `tree` towards `target` until it reaches it or is blocked.
fn connect(
    tree: &mut Tree,
    target: &[f64],
    space: &Space,
    screening: &mut Screening,
    range: f64,
) -> Extend {
    loop {
        match extend(tree, target, space, screening, range, None, None) {
            Extend::Advanced(_) => continue,
            other => return other,
        }
    }
}

/// Outcome of a search.
#[derive(Debug, Clone, PartialEq)]
pub enum RrtResult {
    /// A path from the start to one of the goals (index into `goals`).
    Found {
        /// Waypoints, start first, goal last.
        path: Vec<Vec<f64>>,
        /// Which goal was reached.
        goal: usize,
        /// Samples drawn.
        iterations: usize,
    },
    /// No connection within the iteration budget.
    Exhausted {
        /// Samples drawn.
        iterations: usize,
    },
}

/// Searches a collision-free path from `start` to any of `goals` (all assumed valid).
/// Deterministic for a given `rng` state.
pub fn rrt_connect<R: Rng + ?Sized>(
    start: &[f64],
    goals: &[Vec<f64>],
    space: &Space,
    options: &RrtOptions,
    rng: &mut R,
) -> RrtResult {
    for (g, goal) in goals.iter().enumerate() {
        let points = Screening::points_if_blocked(distance(start, goal), 1.0);
        if space.screened_edge_valid(start, goal, points) {
            return RrtResult::Found {
                path: vec![start.to_vec(), goal.clone()],
                goal: g,
                iterations: 0,
            };
        }
    }
    if goals.is_empty() {
        return RrtResult::Exhausted { iterations: 0 };
    }
    let dof = start.len();
    let mut a = Tree::new(dof);
    a.add(start, NO_PARENT);
    let mut b = Tree::new(dof);
    let mut goal_of_root = Vec::new();
    for goal in goals {
        let root = b.add(goal, NO_PARENT);
        goal_of_root.push((root, goal_of_root.len()));
    }
    // `a_is_start` tracks which tree grows from the start after the swaps.
    let mut a_is_start = true;
    let mut sample = vec![0.0; dof];
    let sampler = space.sampler();
    let mut screening = Screening::default();
    for iteration in 1..=options.max_iterations {
        sampler.fill(rng, &mut sample);
        let domain = options.dynamic_domain.as_ref();
        if let Extend::Advanced(new) | Extend::Reached(new) = extend(
            &mut a,
            &sample,
            space,
            &mut screening,
            options.range,
            domain,
            options.halve_step_after,
        ) {
            let q_new = a.node(new).to_vec();
            if let Extend::Reached(other) =
                connect(&mut b, &q_new, space, &mut screening, options.range)
            {
                let (start_tree, start_node, goal_tree, goal_node) = if a_is_start {
                    (&a, new, &b, other)
                } else {
                    (&b, other, &a, new)
                };
                let mut path = start_tree.path_to(start_node);
                let mut tail = goal_tree.path_to(goal_node);
                tail.reverse();
                // The meeting configuration appears at the end of one and the start of the other.
                path.extend(tail.into_iter().skip(1));
                let root = goal_tree.roots[goal_node];
                let goal = goal_of_root
                    .iter()
                    .find(|(r, _)| *r == root)
                    .map_or(0, |(_, g)| *g);
                return RrtResult::Found {
                    path,
                    goal,
                    iterations: iteration,
                };
            }
        }
        if !options.balance || b.len() < a.len() {
            std::mem::swap(&mut a, &mut b);
            a_is_start = !a_is_start;
        }
    }
    RrtResult::Exhausted {
        iterations: options.max_iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{Checker, Margins, RobotCollision, Scene};
    use crate::contact_rules::Allowances;
    use crate::shortcut::shortcut;
    use crate::Robot;
    use akl_scene::{builtin, Object, Shape};
    use akl_tsr::pose::pose_from_xyz;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The pick-and-place world with a wall that turning joint 1 by 1.2 rad from the ready
    /// pose sweeps the arm through (the other way is free).
    fn beside_a_wall() -> akl_scene::World {
        let mut world = builtin::task("pick_place").unwrap().unwrap().world;
        world.objects.push(Object {
            name: "wall".into(),
            shape: Shape::Box {
                size: [0.4, 0.02, 0.7],
            },
            pose: pose_from_xyz([0.4, 0.2, 0.55]),
            movable: false,
            mass: 0.0,
            friction: 0.5,
        });
        world
    }

    /// Runs `test` with the Panda in [`beside_a_wall`], hand open, nothing held.
    fn beside_the_wall(test: impl FnOnce(&Robot, &Space)) {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let scene = Scene::new(&beside_a_wall(), &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let allow = Allowances::default();
        let space = Space {
            checker: &checker,
            width: robot.open_width(),
            held: None,
            allow: &allow,
        };
        test(&robot, &space);
    }

    /// A sample beyond a node's dynamic domain is turned away unchecked; an extension that
    /// meets an obstacle gives its node the domain's radius, and each later failure narrows it
    /// down to the least radius.
    #[test]
    fn the_dynamic_domain_turns_far_samples_away_and_narrows_on_failure() {
        beside_the_wall(|robot, space| {
            let domain = DynamicDomain {
                radius: 1.5,
                alpha: 0.25,
                min_radius: 1.0,
            };
            let ready = robot.ready().to_vec();
            let mut tree = Tree::new(robot.dof());
            tree.add(&ready, NO_PARENT);
            let mut screening = Screening::default();
            let mut step = |tree: &mut Tree, target: &[f64], domain: Option<&DynamicDomain>| {
                extend(tree, target, space, &mut screening, 2.0, domain, None)
            };
            // Turning joint 1 by 1.2 rad sweeps the arm through the wall.
            let mut blocked = ready.clone();
            blocked[0] += 1.2;
            assert!(matches!(
                step(&mut tree, &blocked, Some(&domain)),
                Extend::Trapped
            ));
            assert_eq!(tree.radii[0], 1.5);
            assert!(matches!(
                step(&mut tree, &blocked, Some(&domain)),
                Extend::Trapped
            ));
            assert_eq!(tree.radii[0], 1.125);
            // Narrowed no further than the least radius (a target within the domain).
            let mut blocked_nearer = ready.clone();
            blocked_nearer[0] += 1.1;
            assert!(matches!(
                step(&mut tree, &blocked_nearer, Some(&domain)),
                Extend::Trapped
            ));
            assert_eq!(tree.radii[0], 1.0);
            // Farther than the radius: turned away, nothing added.
            let mut far = ready.clone();
            far[0] -= 1.1;
            assert!(matches!(
                step(&mut tree, &far, Some(&domain)),
                Extend::Outside
            ));
            assert_eq!(tree.len(), 1);
            // Within it and free: the node grows and its domain widens.
            let mut near = ready.clone();
            near[0] -= 0.5;
            assert!(matches!(
                step(&mut tree, &near, Some(&domain)),
                Extend::Reached(1)
            ));
            assert_eq!(tree.radii[0], 1.25);
            assert!(tree.radii[1].is_infinite());
            // Without a domain nothing is turned away.
            assert!(matches!(
                step(&mut tree, &far, None),
                Extend::Reached(2) | Extend::Advanced(2)
            ));
        });
    }

    /// Extensions from a node that meet an obstacle shrink that node's later steps: after
    /// `halve_after` failures a step is half the range, never below the least step, and a
    /// new node starts with the whole range.
    #[test]
    fn failures_shrink_a_nodes_step() {
        beside_the_wall(|robot, space| {
            let ready = robot.ready().to_vec();
            // Turning joint 1 by 1.2 rad sweeps the arm through the wall; the other way is free.
            let mut blocked = ready.clone();
            blocked[0] += 1.2;
            let mut free = ready.clone();
            free[0] -= 1.5;
            let grow = |halve_after: Option<u32>| {
                let mut tree = Tree::new(robot.dof());
                tree.add(&ready, NO_PARENT);
                let mut screening = Screening::default();
                for _ in 0..2 {
                    let blocked_step = extend(
                        &mut tree,
                        &blocked,
                        space,
                        &mut screening,
                        2.0,
                        None,
                        halve_after,
                    );
                    assert!(matches!(blocked_step, Extend::Trapped));
                }
                let outcome = extend(
                    &mut tree,
                    &free,
                    space,
                    &mut screening,
                    2.0,
                    None,
                    halve_after,
                );
                (tree, outcome)
            };
            // Two failures with halving after two: a step of 1 rad towards the free target.
            let (mut tree, outcome) = grow(Some(2));
            assert!(matches!(outcome, Extend::Advanced(1)));
            assert_eq!(tree.failures[0], 2);
            assert!((distance(tree.node(0), tree.node(1)) - 1.0).abs() < 1e-12);
            assert_eq!(tree.step(1, 2.0, Some(2)), 2.0);
            tree.failures[0] = 100;
            assert_eq!(tree.step(0, 2.0, Some(2)), MIN_STEP);
            // Without halving the whole range: the target is reached.
            let (tree, outcome) = grow(None);
            assert!(matches!(outcome, Extend::Reached(1)));
            assert_eq!(tree.failures[0], 0);
        });
    }

    /// Screening waits until more than half the edges tried are blocked, then follows their
    /// share, and stops for a search whose edges are free.
    #[test]
    fn screening_follows_the_share_of_blocked_edges() {
        let mut screening = Screening::default();
        assert_eq!(screening.points(1.0), 0);
        screening.tried = 99;
        screening.blocked = 75;
        assert_eq!(screening.points(1.0), 4);
        screening.blocked = 99;
        assert_eq!(screening.points(1.0), 7);
        assert_eq!(screening.points(2.0), SCREEN_MAX);
        assert_eq!(screening.points(0.1), 0);
        screening.blocked = 0;
        assert_eq!(screening.points(1.0), 0);
    }

    /// Every path RRT-Connect returns between random collision-free configurations, as found
    /// and after shortcutting, joins the start to the goal and keeps half of every margin under
    /// a re-check dense enough that no point moves more than a tenth of the smallest margin
    /// between two samples; and with the default budget it finds one every time. Seeds 0–15
    /// and 82996 (where parry's intersection test once reported a path free by the planner's
    /// proof as colliding, see `parry_convert::intersects`).
    #[test]
    fn returned_paths_are_found_and_free_under_a_dense_recheck() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let m = model.margins();
        let half = RobotCollision::with_margins(
            &robot,
            Margins {
                arm: m.arm / 2.0,
                hand: m.hand / 2.0,
                held: m.held / 2.0,
                self_: m.self_ / 2.0,
            },
        );
        let mut world = builtin::task("pick_place").unwrap().unwrap().world;
        world.objects.push(Object {
            name: "pole".into(),
            shape: Shape::Box {
                size: [0.04, 0.04, 0.6],
            },
            pose: pose_from_xyz([0.40, 0.12, 0.3]),
            movable: false,
            mass: 0.0,
            friction: 0.5,
        });
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let dense = Checker::new(&robot, &half, &scene);
        let allow = Allowances::default();
        let width = robot.open_width();
        let space = Space {
            checker: &checker,
            width,
            held: None,
            allow: &allow,
        };
        let sampler = space.sampler();
        for seed in (0..16u64).chain([82996]) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut free = || {
                let mut q = vec![0.0; robot.dof()];
                loop {
                    sampler.fill(&mut rng, &mut q);
                    if space.valid(&q) {
                        return q;
                    }
                }
            };
            let (start, goal) = (free(), free());
            let found = rrt_connect(
                &start,
                std::slice::from_ref(&goal),
                &space,
                &RrtOptions::default(),
                &mut rng,
            );
            let RrtResult::Found { path, .. } = found else {
                panic!("seed {seed}: no path within the default budget");
            };
            let short = shortcut(path.clone(), &space, 50, &mut rng);
            let smallest = m.arm.min(m.hand).min(m.self_ / 2.0);
            for p in [path, short] {
                assert_eq!(&p[0], &start, "seed {seed}");
                assert_eq!(&p[p.len() - 1], &goal, "seed {seed}");
                for w in p.windows(2) {
                    let n = (10.0 * checker.sweep_bound(&w[0], &w[1], width, None) / smallest)
                        .ceil() as usize;
                    for k in 0..=n {
                        let s = k as f64 / n.max(1) as f64;
                        let q: Vec<f64> = w[0]
                            .iter()
                            .zip(&w[1])
                            .map(|(x, y)| x + s * (y - x))
                            .collect();
                        assert_eq!(dense.check(&q, width, None, &allow), None, "seed {seed}");
                    }
                }
            }
        }
    }
}
