//! Re-checking a timed plan densely, independently of how it was planned: collisions (with
//! the clearance the planner guarantees, half of each margin), joint limits, velocity and
//! acceleration limits, and the distance of straight segments from their lines.

use crate::collision::{Checker, Held, Margins, RobotCollision, Scene};
use crate::line::distance_to_segment;
use crate::plan::{GripperAction, Plan, Segment};
use crate::robot::Robot;
use akl_scene::World;
use std::fmt;

/// Settings of [`recheck`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RecheckOptions {
    /// Time between samples (seconds).
    pub dt: f64,
    /// Fraction of each margin that must stay clear (the planner guarantees one half).
    pub margin_fraction: f64,
    /// Largest distance of a straight segment's TCP from its line (metres).
    pub line_tolerance: f64,
    /// Relative slack on the velocity and acceleration limits (finite differences).
    pub limit_slack: f64,
}

impl Default for RecheckOptions {
    fn default() -> Self {
        RecheckOptions {
            dt: 5e-4,
            margin_fraction: 0.5,
            line_tolerance: 1e-3,
            limit_slack: 0.02,
        }
    }
}

/// A problem found in a plan, with the time and segment where it occurs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Violation {
    /// Seconds from the start of the plan.
    pub t: f64,
    /// Index of the segment.
    pub segment: usize,
    /// What is wrong.
    pub problem: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "t = {:.3} s, segment {}: {}",
            self.t, self.segment, self.problem
        )
    }
}

/// The world during `segment`: objects released before it stand where they were placed.
fn world_during(world: &World, plan: &Plan, segment: &Segment) -> World {
    let mut w = world.clone();
    for e in plan.events.iter().filter(|e| e.t < segment.start) {
        if e.action == GripperAction::Open {
            if let Some(o) = w.object_mut(&e.object) {
                o.pose = e.object_pose;
            }
        }
    }
    w
}

/// The object held during `segment`, placed as it was grasped.
fn held_during(world: &World, plan: &Plan, segment: &Segment, margins: &Margins) -> Option<Held> {
    let name = segment.holding.as_ref()?;
    let grasp = plan
        .events
        .iter()
        .rfind(|e| e.action == GripperAction::Close && e.object == *name && e.t <= segment.start)?;
    let shape = world.object(name)?.shape.clone();
    Some(Held::new(name, shape, grasp.object_pose, margins))
}

/// Every violation found when sampling `plan` every `options.dt` seconds in `world` (the
/// world the plan was made for).
pub(crate) fn recheck(
    robot: &Robot,
    world: &World,
    plan: &Plan,
    options: &RecheckOptions,
) -> Vec<Violation> {
    let c = &robot.config().collision;
    let f = options.margin_fraction;
    let model = RobotCollision::with_margins(
        robot,
        Margins {
            arm: f * c.arm_margin,
            hand: f * c.hand_margin,
            held: f * c.held_margin,
            self_: f * c.self_margin,
        },
    );
    let mut found = Vec::new();
    let mut previous: Vec<Vec<f64>> = Vec::new();
    let (vmax, amax) = (robot.velocity_limits(), robot.acceleration_limits());
    let base = world.robot_base;
    for (k, segment) in plan.segments.iter().enumerate() {
        let w = world_during(world, plan, segment);
        let held = held_during(world, plan, segment, &model.margins());
        let without: Vec<&str> = held.iter().map(|h| h.name.as_str()).collect();
        let scene = Scene::new(&w, &without);
        let checker = Checker::new(robot, &model, &scene);
        let duration = segment.end - segment.start;
        let n = (duration / options.dt).ceil().max(1.0) as usize;
        for s in 0..=n {
            let local = duration * s as f64 / n as f64;
            let t = segment.start + local;
            let q = segment.timing.sample(&segment.waypoints, local);
            let mut report = |problem: String| {
                found.push(Violation {
                    t,
                    segment: k,
                    problem,
                })
            };
            if let Err(e) = robot.check_joints(&q) {
                report(e.to_string());
            }
            if let Some(hit) =
                checker.check(&q, plan.gripper_width(t), held.as_ref(), &segment.allowed)
            {
                report(format!("collision: {hit}"));
            }
            if let Some(line) = &segment.line {
                let p = (base * robot.tcp_pose(&q)).translation.vector;
                let d = distance_to_segment(
                    &p,
                    &line.from.translation.vector,
                    &line.to.translation.vector,
                );
                if d > options.line_tolerance {
                    report(format!("{:.2} mm from its line", d * 1e3));
                }
            }
            // Finite differences over samples spaced dt apart (only within a segment, whose
            // sample spacing is uniform).
            if s > 0 {
                let h = duration / n as f64;
                if let Some(prev) = previous.last() {
                    for j in 0..q.len() {
                        let v = (q[j] - prev[j]) / h;
                        if v.abs() > vmax[j] * (1.0 + options.limit_slack) {
                            report(format!(
                                "joint {} at {v:.3}, beyond its velocity limit {}",
                                j + 1,
                                vmax[j]
                            ));
                        }
                    }
                }
                if previous.len() >= 2 {
                    let (a, b) = (&previous[previous.len() - 2], &previous[previous.len() - 1]);
                    for j in 0..q.len() {
                        let acc = (q[j] - 2.0 * b[j] + a[j]) / (h * h);
                        if acc.abs() > amax[j] * (1.0 + options.limit_slack) {
                            report(format!(
                                "joint {} at {acc:.3}, beyond its acceleration limit {}",
                                j + 1,
                                amax[j]
                            ));
                        }
                    }
                }
            } else {
                previous.clear();
            }
            previous.push(q);
            if previous.len() > 2 {
                previous.remove(0);
            }
        }
    }
    found
}
