//! Planning one candidate of a whole task spec (`plan_candidate`; [`crate::search::plan_task`] keeps the best of several).
//!
//! The arm starts at the robot's ready configuration with the gripper open. Keyframes are
//! handled in order, each grounded on the objects' current poses (objects move when they
//! are carried and released):
//!
//! - A keyframe whose gripper closes after being open is a grasp of its reference object;
//!   one whose gripper opens after being closed releases the held object onto its reference
//!   (the support). From a grasp until the release the object moves rigidly with the TCP and
//!   is checked against the world and the arm (never against the hand holding it).
//! - A `move_in_line` keyframe is reached by a straight TCP line from where the previous one
//!   left the TCP to a pose of its TSR (see `line`). Any other keyframe is reached by a free
//!   motion: goal configurations are sampled from its TSR (`goal`), RRT-Connect finds a path
//!   (`rrt`) and shortcutting shortens it (`shortcut`). A grasp or release pose drawn from its
//!   TSR is first moved within it to where a linkage's knuckles clear the object, or the held
//!   object rests on its support (`fit`).
//! - A grasp or release reached by free motion is approached along the tool's z axis from a
//!   pose `approach_distance` back; the free motion ends there, fully checked. After a grasp
//!   the object is lifted back along the same path, unless the next keyframe starts a line
//!   (a combined keyframe: the line itself carries it away). After a release the hand
//!   retreats the same way.
//!
//! Contacts that are allowed, and only where stated:
//! - the hand links with the object being grasped, on the approach and at the grasp (the
//!   finger capsules pass the object's sides), and on a line that ends in a grasp;
//! - the hand links with the object just released, on the retreat;
//! - the held object with the support it was lifted from, until it has been lifted (on the
//!   lift, or along the lines that slide it before any lift);
//! - the held object with the support it is released onto, on the approach to the release
//!   and along a line that ends in the release.
//!
//! Every segment starts and ends at rest; free segments stop at their waypoints, straight
//! segments follow a monotone cubic through their dense waypoints (see `timing`). The
//! gripper takes its travel time plus a settling pause at each event, the arm standing still.
//! Everything is deterministic for a given seed.

mod fit;
mod free;
mod gripper;
mod lines;
mod segments;
#[cfg(test)]
mod tests;

use crate::collision::{Checker, Held, RobotCollision, Scene};
use crate::contact_rules::{Allowances, Step};
use crate::error::PlanError;
use crate::goal::GoalStrategy;
use crate::hand::HandModel;
use crate::line::LineFailure;
use crate::options::PlanOptions;
use crate::plan::{GripperEvent, LinePoses, Plan, Segment, PLAN_VERSION};
use crate::robot::Robot;
use crate::squeeze::squared_in_hand;
use akl_scene::{Shape, World};
use akl_tsr::nalgebra::{Translation3, Vector3};
use akl_tsr::{Constraint, Gripper, Keyframe, Pose, TaskSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::cell::Cell;
use std::time::Instant;

/// The object in the hand.
#[derive(Debug, Clone)]
struct Holding {
    held: Held,
    /// The support it still rests on (not yet lifted).
    resting_on: Option<String>,
}

/// What happens at a keyframe.
#[derive(Debug, Clone, PartialEq)]
enum Event {
    Grasp {
        object: String,
    },
    Release {
        support: String,
        /// What the support stands on.
        beneath: Option<String>,
    },
}

/// A straight TCP segment: joint waypoints, grounded end poses and the contacts it allows.
#[derive(Debug, Clone)]
struct PlannedLine {
    path: Vec<Vec<f64>>,
    poses: LinePoses,
    allow: Allowances,
}

/// Joint paths validated with a goal candidate.
#[derive(Debug, Clone)]
struct GoalPaths {
    /// Where the free motion ends.
    free_goal: Vec<f64>,
    /// From the free goal onto the keyframe (approach), if any.
    approach: Option<Vec<Vec<f64>>>,
    /// The line to the next keyframe, planned ahead from this candidate.
    next_line: Option<PlannedLine>,
}

struct Planner<'a> {
    robot: &'a Robot,
    model: RobotCollision,
    options: &'a PlanOptions,
    rng: ChaCha8Rng,
    q: Vec<f64>,
    world: World,
    gripper: Gripper,
    width: f64,
    holding: Option<Holding>,
    segments: Vec<Segment>,
    events: Vec<GripperEvent>,
    t: f64,
    /// A line to the next keyframe already planned by the look-ahead.
    pending_line: Option<PlannedLine>,
    /// An object released with no retreat (a line follows): the hand may touch it on that line.
    just_released: Option<String>,
    /// Configurations probed for collisions so far (the caller's count, see
    /// [`crate::search::BestPlan::probes`]).
    probes: &'a Cell<u64>,
    /// The hand, whose linkage must keep clear of what the pads close on.
    hand: Option<HandModel>,
}

/// Plans one candidate: every keyframe in turn, its goals chosen by
/// `options.goals.strategy`, every random choice drawn from `options.seed`; adds the
/// configurations it probes for collisions to `probes`.
pub(crate) fn plan_candidate(
    robot: &Robot,
    spec: &TaskSpec,
    world: &World,
    options: &PlanOptions,
    probes: &Cell<u64>,
) -> Result<Plan, PlanError> {
    let mut planner = Planner::new(robot, world.clone(), options, probes);
    spec.validate()
        .and_then(|()| spec.check_references(world.names()))
        .map_err(|e| PlanError::Grounding(e.to_string()))?;
    planner.check_start()?;
    for i in 0..spec.keyframes.len() {
        let grounded = spec
            .ground(&planner.world.object_poses())
            .map_err(|e| PlanError::Grounding(e.to_string()))?;
        planner.keyframe(&grounded.keyframes, i)?;
    }
    Ok(Plan {
        akl_plan: PLAN_VERSION,
        task: spec.task.clone(),
        robot: robot.name().to_string(),
        joint_names: robot.joint_names().to_vec(),
        seed: options.seed,
        duration: planner.t,
        segments: planner.segments,
        events: planner.events,
    })
}

/// The pose `distance` back along the tool z axis from `pose`.
fn backed_off(pose: &Pose, distance: f64) -> Pose {
    pose * Translation3::new(0.0, 0.0, -distance)
}

/// The object's extent along the fingers' closing direction (the TCP y axis): the opening the
/// gripper closes to.
fn grasp_width(shape: &Shape, object: &Pose, tcp: &Pose) -> f64 {
    let u = object.rotation.inverse() * (tcp.rotation * Vector3::y());
    match *shape {
        Shape::Box { size } => u.x.abs() * size[0] + u.y.abs() * size[1] + u.z.abs() * size[2],
        Shape::Cylinder { radius, length } => {
            u.z.abs() * length + 2.0 * radius * (1.0 - u.z * u.z).max(0.0).sqrt()
        }
        Shape::Capsule { radius, length } => u.z.abs() * length + 2.0 * radius,
        Shape::Sphere { radius } => 2.0 * radius,
        Shape::Mesh { ref hull, .. } => hull.as_ref().map_or(0.0, |h| {
            let along = h.vertices.iter().map(|v| v.coords.dot(&u));
            let (lo, hi) = along.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            });
            hi - lo
        }),
    }
}

/// How far the object's middle between the pads lies from the fingers' midline (along the
/// TCP y axis), which the fingers push it across as they close: for a cylinder or capsule, the
/// point of its axis nearest the TCP (a long one tilted across the fingers is held there, not
/// at its centre); for other shapes their centre.
fn centring_offset(shape: &Shape, object: &Pose, tcp: &Pose) -> f64 {
    let local = tcp.inverse() * object;
    let centre = local.translation.vector;
    let middle = match *shape {
        Shape::Cylinder { .. } | Shape::Capsule { .. } => {
            let axis = local.rotation * Vector3::z();
            centre - axis * centre.dot(&axis)
        }
        _ => centre,
    };
    middle.y.abs()
}

/// Where an object grasped with the TCP at `tcp` sits in the TCP frame once the fingers have
/// closed on it: a parallel gripper pushes what it closes on to the middle between its fingers,
/// so the object's centre ends on the closing axis's midpoint (TCP y = 0), whatever error its
/// perceived pose had along that axis; and its squeeze lays the object flat on the pads
/// ([`squared_in_hand`]), as the simulation's grasp does.
fn centred_in_hand(tcp: &Pose, object: &Pose, shape: &Shape) -> Pose {
    let mut in_tcp = squared_in_hand(shape, &(tcp.inverse() * object));
    in_tcp.translation.vector.y = 0.0;
    in_tcp
}

/// A line's failure as the planning error of keyframe `keyframe`, naming the segment.
fn line_error(keyframe: usize, segment: String, failure: &LineFailure) -> PlanError {
    PlanError::Line {
        keyframe,
        segment,
        reason: failure.to_string(),
    }
}

impl Step<'_> {
    /// What a step reaching keyframe with `event` manipulates: the object it grasps, or the
    /// support it puts the held object on.
    fn at(event: Option<&Event>) -> Step<'_> {
        match event {
            Some(Event::Grasp { object }) => Step {
                grasping: Some(object),
                ..Step::default()
            },
            Some(Event::Release { support, beneath }) => Step {
                placing_on: Some(support),
                beneath: beneath.as_deref(),
                ..Step::default()
            },
            None => Step::default(),
        }
    }
}

impl<'a> Planner<'a> {
    /// A planner at the robot's ready configuration, hand open and empty, nothing planned yet,
    /// its random choices drawn from `options.seed`.
    fn new(
        robot: &'a Robot,
        world: World,
        options: &'a PlanOptions,
        probes: &'a Cell<u64>,
    ) -> Planner<'a> {
        Planner {
            robot,
            model: RobotCollision::new(robot),
            options,
            rng: ChaCha8Rng::seed_from_u64(options.seed),
            q: robot.ready().to_vec(),
            world,
            gripper: Gripper::Open,
            width: robot.open_width(),
            holding: None,
            segments: Vec::new(),
            events: Vec::new(),
            t: 0.0,
            pending_line: None,
            just_released: None,
            probes,
            hand: HandModel::new(robot),
        }
    }

    fn base(&self) -> Pose {
        self.world.robot_base
    }

    /// What `support` stands on in the world planned in, if anything.
    fn beneath(&self, support: &str) -> Option<String> {
        self.world.support_of(support).map(|o| o.name.clone())
    }

    fn tcp_world(&self, q: &[f64]) -> Pose {
        self.base() * self.robot.tcp_pose(q)
    }

    /// Whether the gripper can close on `object` of `world` with the TCP at `pose`: the parts of a
    /// linkage other than its pads keep the held object's margin from the object (about to be
    /// held: the margin kept between a held object and the arm) at every opening of the
    /// closing, with the object as it stands and as the squeeze turns it
    /// ([`Planner::linkage_clearance`]). Prismatic fingers always can (only their pads move).
    fn check_closing(&self, world: &World, object: &str, pose: &Pose) -> Result<(), String> {
        let margin = self.model.margins().held;
        match self.linkage_clearance(world, object, pose) {
            Some(c) if c.clearance < margin => Err(format!(
                "closing on {object}: {} comes within {:.1} mm of it (a held object keeps {:.1} mm)",
                self.robot.links()[c.link].name,
                c.clearance.max(0.0) * 1e3,
                margin * 1e3
            )),
            _ => Ok(()),
        }
    }

    fn held(&self) -> Option<&Held> {
        self.holding.as_ref().map(|h| &h.held)
    }

    fn scene(&self) -> Scene {
        let without: Vec<&str> = self.holding.iter().map(|h| h.held.name.as_str()).collect();
        Scene::new(&self.world, &without)
    }

    fn check_start(&self) -> Result<(), PlanError> {
        self.robot
            .check_joints(&self.q)
            .map_err(|e| PlanError::Start(e.to_string()))?;
        let scene = self.scene();
        let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
        match checker.check(&self.q, self.width, None, &Allowances::default()) {
            Some(hit) => Err(PlanError::Start(format!(
                "the ready configuration collides: {hit}"
            ))),
            None => Ok(()),
        }
    }

    fn event_at(&self, keyframes: &[Keyframe], i: usize) -> Result<Option<Event>, PlanError> {
        let kf = &keyframes[i];
        match (self.gripper, kf.gripper) {
            (Gripper::Open, Gripper::Closed) => {
                let movable = self.world.object(&kf.reference).is_some_and(|o| o.movable);
                if !movable {
                    return Err(PlanError::Invalid {
                        keyframe: i,
                        reason: format!(
                            "the gripper closes on `{}`, which is not a movable object",
                            kf.reference
                        ),
                    });
                }
                Ok(Some(Event::Grasp {
                    object: kf.reference.clone(),
                }))
            }
            (Gripper::Closed, Gripper::Open) => Ok(Some(Event::Release {
                support: kf.reference.clone(),
                beneath: self.beneath(&kf.reference),
            })),
            _ => Ok(None),
        }
    }

    /// The keyframe's own stream of goal draws with [`GoalStrategy::Sampled`] (see
    /// [`crate::goal::keyframe_stream`]); with the other strategies goals come from the
    /// planner's stream.
    fn sampled_stream(&self, kf: &Keyframe) -> Option<ChaCha8Rng> {
        (self.options.goals.strategy == GoalStrategy::Sampled)
            .then(|| crate::goal::keyframe_stream(self.options.seed, kf))
    }

    fn keyframe(&mut self, keyframes: &[Keyframe], i: usize) -> Result<(), PlanError> {
        let kf = &keyframes[i];
        let event = self.event_at(keyframes, i)?;
        let next_line = keyframes
            .get(i + 1)
            .is_some_and(|k| k.constraint == Constraint::MoveInLine);
        let started = Instant::now();
        let approach = match kf.constraint {
            Constraint::MoveInLine => {
                self.reach_by_line(kf, i, event.as_ref(), started)?;
                None
            }
            Constraint::None => {
                let next = if next_line {
                    keyframes.get(i + 1)
                } else {
                    None
                };
                self.reach_by_free_motion(kf, i, event.as_ref(), next, started)?
            }
        };
        self.just_released = None;
        match event {
            Some(Event::Grasp { object }) => self.grasp(i, &object, approach, next_line),
            Some(Event::Release { support, .. }) => self.release(i, &support, approach, next_line),
            None => Ok(()),
        }?;
        self.gripper = kf.gripper;
        Ok(())
    }
}
