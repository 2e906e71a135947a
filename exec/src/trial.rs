//! One trial: plan the spec in a world, simulate the plan, verify the execution.
//!
//! The simulation follows the plan at a fixed time step: the arm's kinematic links are set
//! to the planned joints, a grasp attaches the object between the fingers once they have
//! closed, a release lets it go when they start to open. After the plan, physics settles
//! the objects for [`ExecOptions::settle`] seconds before the goals are checked.

use crate::arm::Arm;
use crate::contacts::{ContactLog, ContactRules};
use crate::grasp::{FingerGap, Held};
use crate::report::{Cause, Failure, GraspCheck, KeyframeCheck, TrialReport};
use crate::verify::{check_goals, check_keyframe, check_line, check_rest};
use crate::world::{Physics, SimWorld};
use akl_planner::collision::Allowances;
use akl_planner::{plan_task, GripperAction, Plan, PlanError, PlanOptions, Robot, SegmentKind};
use akl_scene::{ObjectPaths, Task, World};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Pose, PoseJson, TaskSpec, WORLD_FRAME};
use std::time::Instant;

/// Settings of execution.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecOptions {
    /// Simulation settings.
    pub physics: Physics,
    /// Planner settings (the seed is replaced by each trial's).
    pub plan: PlanOptions,
    /// How far the TCP may leave a `move_in_line` segment's line (metres).
    pub line_tolerance: f64,
    /// Simulated seconds of settling after the plan, before the goals are checked.
    pub settle: f64,
    /// Speed below which an object counts as at rest (m/s; ten times that in rad/s).
    pub rest_speed: f64,
}

impl Default for ExecOptions {
    fn default() -> Self {
        ExecOptions {
            physics: Physics::default(),
            plan: PlanOptions::default(),
            line_tolerance: 0.005,
            settle: 0.5,
            rest_speed: 0.01,
        }
    }
}

/// What a trial needs besides its world: the robot, the task and the spec.
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a> {
    /// The robot.
    pub robot: &'a Robot,
    /// The task (its nominal world, goals and ranges).
    pub task: &'a Task,
    /// The spec executed.
    pub spec: &'a TaskSpec,
    /// Settings.
    pub options: &'a ExecOptions,
}

/// The poses of one instant of a simulation, for a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Simulated time (seconds).
    pub t: f64,
    /// World pose of every robot link, in the robot's link order.
    pub links: Vec<Pose>,
    /// World pose of every object, in the task's order.
    pub objects: Vec<Pose>,
}

/// Frames of a simulation recorded at a fixed rate, with the plan that drove it.
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Frames per simulated second.
    pub rate: f64,
    /// The frames, in time order.
    pub frames: Vec<Frame>,
    /// The plan executed, when there was one.
    pub plan: Option<Plan>,
}

impl Timeline {
    /// An empty timeline recording `rate` frames per simulated second.
    pub fn new(rate: f64) -> Timeline {
        Timeline {
            rate,
            frames: Vec::new(),
            plan: None,
        }
    }
}

/// The cause a planning error counts under: unreachable when no pose of a keyframe's TSR has
/// an IK solution; collision when poses are reachable but every solution (or its approach)
/// would make the arm or the held object touch something, which the planner finds before
/// the simulation could; no plan for the rest (budget exhausted, a line that cannot be
/// followed, a bad start).
pub fn plan_cause(e: &PlanError) -> Cause {
    match e {
        PlanError::Unreachable { .. } => Cause::Unreachable,
        PlanError::NoCollisionFreeIk { .. } => Cause::Collision,
        _ => Cause::NoPlan,
    }
}

/// Runs trial `trial` with objects placed as in `world`, planning with `seed`; records
/// frames into `timeline` when given.
pub fn run_trial(
    setup: &Setup,
    trial: usize,
    seed: u64,
    world: &World,
    timeline: Option<&mut Timeline>,
) -> TrialReport {
    let placements = setup
        .task
        .randomize
        .keys()
        .filter_map(|n| world.object(n))
        .map(|o| (o.name.clone(), PoseJson::from_pose(&o.pose)))
        .collect();
    let mut report = TrialReport {
        trial,
        seed,
        passed: false,
        failures: Vec::new(),
        placements,
        plan_seconds: 0.0,
        sim_seconds: 0.0,
        simulated_seconds: 0.0,
        keyframes: Vec::new(),
        lines: Vec::new(),
        grasps: Vec::new(),
        collisions: Vec::new(),
        goals: Vec::new(),
    };
    let options = PlanOptions {
        seed,
        ..setup.options.plan.clone()
    };
    let started = Instant::now();
    let planned = plan_task(setup.robot, setup.spec, world, &options);
    report.plan_seconds = started.elapsed().as_secs_f64();
    match planned {
        Ok(plan) => {
            let started = Instant::now();
            Execution::new(setup, world, &plan).run(&mut report, timeline, &plan);
            report.sim_seconds = started.elapsed().as_secs_f64();
        }
        Err(e) => report.failures.push(Failure {
            cause: plan_cause(&e),
            detail: e.to_string(),
        }),
    }
    report.passed = report.failures.is_empty();
    report
}

/// A label for a plan segment, e.g. `free motion to keyframe 2` or `lift after keyframe 0`.
fn segment_label(kind: SegmentKind, keyframe: usize) -> String {
    match kind {
        SegmentKind::Free => format!("free motion to keyframe {keyframe}"),
        SegmentKind::Line => format!("line to keyframe {keyframe}"),
        SegmentKind::Approach => format!("approach to keyframe {keyframe}"),
        SegmentKind::Lift => format!("lift after keyframe {keyframe}"),
        SegmentKind::Retreat => format!("retreat after keyframe {keyframe}"),
        SegmentKind::Gripper => format!("gripper at keyframe {keyframe}"),
    }
}

/// When the plan reaches a keyframe: the end of the last motion segment that leads to it.
fn reach_times(plan: &Plan, keyframes: usize) -> Vec<Option<f64>> {
    let mut times = vec![None; keyframes];
    for s in &plan.segments {
        let leads_to = matches!(
            s.kind,
            SegmentKind::Free | SegmentKind::Approach | SegmentKind::Line
        );
        if leads_to && s.keyframe < keyframes {
            times[s.keyframe] = Some(s.end);
        }
    }
    times
}

/// What happens to the gripper, and when, in simulation terms.
#[derive(Debug, Clone)]
enum Action {
    /// The fingers have closed: grasp what is between them (the plan expects `object`).
    Grasp { keyframe: usize, object: String },
    /// The fingers start to open: let go.
    Release,
}

/// The state of one simulated execution of a plan.
struct Execution<'a> {
    setup: &'a Setup<'a>,
    sim: SimWorld,
    arm: Arm,
    rules: ContactRules,
    contacts: ContactLog,
    held: Option<Held>,
    /// Gripper actions by time.
    actions: Vec<(f64, Action)>,
    /// Contacts each segment allows, by segment index.
    allowed: Vec<Allowances>,
    /// Objects (indices) the hand may touch, and passes through, in each segment.
    hand_passes: Vec<Vec<usize>>,
    labels: Vec<String>,
}

impl<'a> Execution<'a> {
    fn new(setup: &'a Setup<'a>, world: &World, plan: &Plan) -> Execution<'a> {
        let mut sim = SimWorld::new(world, &setup.options.physics);
        let arm = Arm::new(
            &mut sim,
            setup.robot,
            world.robot_base,
            &plan.sample(0.0),
            plan.gripper_width(0.0),
        );
        let mut actions = Vec::new();
        for e in &plan.events {
            match e.action {
                GripperAction::Close => {
                    let closed = plan
                        .segments
                        .iter()
                        .find(|s| s.kind == SegmentKind::Gripper && s.start >= e.t - 1e-9)
                        .map_or(e.t, |s| s.end);
                    actions.push((
                        closed,
                        Action::Grasp {
                            keyframe: e.keyframe,
                            object: e.object.clone(),
                        },
                    ));
                }
                GripperAction::Open => actions.push((e.t, Action::Release)),
            }
        }
        actions.sort_by(|a, b| a.0.total_cmp(&b.0));
        let allowed: Vec<Allowances> = plan
            .segments
            .iter()
            .map(|s| {
                let mut a = s.allowed.clone();
                if s.kind == SegmentKind::Gripper {
                    // While the fingers close on or open from an object, they touch it.
                    a.hand_may_touch.extend(
                        plan.events
                            .iter()
                            .filter(|e| e.keyframe == s.keyframe)
                            .map(|e| e.object.clone()),
                    );
                }
                a
            })
            .collect();
        let hand_passes = allowed
            .iter()
            .map(|a| {
                a.hand_may_touch
                    .iter()
                    .filter_map(|n| sim.object_index(n))
                    .collect()
            })
            .collect();
        let labels = plan
            .segments
            .iter()
            .map(|s| segment_label(s.kind, s.keyframe))
            .collect();
        Execution {
            setup,
            rules: ContactRules::new(setup.robot, world),
            sim,
            arm,
            contacts: ContactLog::default(),
            held: None,
            actions,
            allowed,
            hand_passes,
            labels,
        }
    }

    fn tcp_at(&self, plan: &Plan, t: f64) -> Pose {
        self.sim.template().robot_base * self.setup.robot.tcp_pose(&plan.sample(t))
    }

    fn reference_pose(&self, name: &str) -> Option<Pose> {
        if name == WORLD_FRAME {
            return Some(Pose::identity());
        }
        self.sim.object_index(name).map(|i| self.sim.object_pose(i))
    }

    fn grasp(&mut self, report: &mut TrialReport, keyframe: usize, planned: &str, width: f64) {
        let tcp = self.arm.tcp();
        let planned_index = self.sim.object_index(planned);
        let gap = FingerGap::new(self.setup.robot, width);
        let inside = |i: usize| gap.is_some_and(|g| g.holds(&self.sim, &tcp, i));
        let grasped = planned_index.filter(|&i| inside(i)).or_else(|| {
            (0..self.sim.objects.len())
                .find(|&i| self.sim.objects[i].movable && Some(i) != planned_index && inside(i))
        });
        let name = grasped.map(|i| self.sim.objects[i].name.clone());
        match &name {
            Some(n) if n == planned => {}
            Some(n) => report.failures.push(Failure {
                cause: Cause::GraspFailed,
                detail: format!(
                    "keyframe {keyframe}: the gripper closed on {n} instead of {planned}"
                ),
            }),
            None => report.failures.push(Failure {
                cause: Cause::GraspFailed,
                detail: format!(
                    "keyframe {keyframe}: the gripper closed on nothing ({planned} is not between the fingers)"
                ),
            }),
        }
        report.grasps.push(GraspCheck {
            keyframe,
            t: self.sim.time(),
            planned: planned.to_string(),
            grasped: name,
        });
        if let Some(i) = grasped {
            self.held = Some(Held::attach(&mut self.sim, i, &tcp));
        }
    }

    fn run(mut self, report: &mut TrialReport, mut timeline: Option<&mut Timeline>, plan: &Plan) {
        let spec = self.setup.spec;
        let options = self.setup.options;
        let dt = self.sim.dt();
        let total = plan.duration + options.settle;
        let steps = (total / dt).ceil() as usize;
        let reaches = reach_times(plan, spec.keyframes.len());
        let mut reached = vec![false; spec.keyframes.len()];
        let mut next_action = 0;
        let mut line_paths: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); plan.segments.len()];
        let mut next_frame = 0.0;
        let mut paths = ObjectPaths::new();
        if let Some(tl) = timeline.as_deref_mut() {
            tl.plan = Some(plan.clone());
        }
        for step in 0..=steps {
            let t = self.sim.time();
            // Actions due before the end of the coming step happen now: the arm stands
            // still around them, and a grasp must hold before the lift's first step.
            while let Some((at, action)) = self.actions.get(next_action).cloned() {
                if at > t + dt - 1e-9 {
                    break;
                }
                next_action += 1;
                match action {
                    Action::Grasp { keyframe, object } => {
                        self.grasp(report, keyframe, &object, plan.gripper_width(at))
                    }
                    Action::Release => {
                        if let Some(h) = self.held.take() {
                            h.release(&mut self.sim);
                        }
                    }
                }
            }
            for (k, at) in reaches.iter().enumerate() {
                match at {
                    Some(at) if !reached[k] && *at <= t + 0.5 * dt => {
                        reached[k] = true;
                        report.keyframes.push(self.keyframe_check(plan, k, *at));
                    }
                    _ => {}
                }
            }
            if let Some(tl) = timeline.as_deref_mut() {
                if t + 1e-9 >= next_frame {
                    tl.frames.push(Frame {
                        t,
                        links: self.arm.link_poses().to_vec(),
                        objects: (0..self.sim.objects.len())
                            .map(|i| self.sim.object_pose(i))
                            .collect(),
                    });
                    next_frame += 1.0 / tl.rate;
                }
            }
            if step == steps {
                break;
            }
            let t_next = t + dt;
            let seg = plan
                .segments
                .partition_point(|s| s.end < t_next)
                .min(plan.segments.len().saturating_sub(1));
            if let Some(pass) = self.hand_passes.get(seg) {
                self.sim.set_hand_passes(pass);
            }
            let q = plan.sample(t_next);
            let width = plan.gripper_width(t_next);
            self.arm.drive(&mut self.sim, self.setup.robot, &q, width);
            let tcp = self.arm.tcp();
            if let Some(h) = &self.held {
                h.follow(&mut self.sim, &tcp);
            }
            self.sim.step();
            for (i, o) in self
                .sim
                .objects
                .iter()
                .enumerate()
                .filter(|(_, o)| o.movable)
            {
                paths.push(&o.name, t_next, self.sim.object_pose(i));
            }
            if let (Some(allowed), Some(label)) = (self.allowed.get(seg), self.labels.get(seg)) {
                let held = self.held.map(|h| h.object);
                self.contacts
                    .scan(&self.sim, &self.rules, held, allowed, t_next, label);
            }
            if plan
                .segments
                .get(seg)
                .is_some_and(|s| s.kind == SegmentKind::Line)
            {
                line_paths[seg].push(tcp.translation.vector);
            }
        }
        for (k, at) in reaches.iter().enumerate() {
            if at.is_none() {
                report.failures.push(Failure {
                    cause: Cause::KeyframeMissed,
                    detail: format!("keyframe {k}: the plan never reaches it"),
                });
            }
        }
        for c in &report.keyframes {
            if !c.reached {
                report.failures.push(Failure {
                    cause: Cause::KeyframeMissed,
                    detail: format!(
                        "keyframe {}: the TCP is {:.1} mm from its TSR grounded on {}'s current pose",
                        c.keyframe,
                        c.distance * 1e3,
                        c.reference
                    ),
                });
            }
        }
        for (s, path) in plan.segments.iter().zip(&line_paths) {
            if s.kind != SegmentKind::Line {
                continue;
            }
            let from = self.tcp_at(plan, s.start).translation.vector;
            let to = self.tcp_at(plan, s.end).translation.vector;
            let check = check_line(
                s.keyframe,
                (s.start, s.end),
                &from,
                &to,
                path,
                options.line_tolerance,
            );
            if !check.within {
                report.failures.push(Failure {
                    cause: Cause::LineDeviation,
                    detail: format!(
                        "line to keyframe {}: the TCP strays {:.1} mm from the line (tolerance {:.1} mm)",
                        s.keyframe,
                        check.deviation * 1e3,
                        options.line_tolerance * 1e3
                    ),
                });
            }
            report.lines.push(check);
        }
        for c in self.contacts.collisions() {
            report.failures.push(Failure {
                cause: Cause::Collision,
                detail: format!(
                    "{} touched {} at {:.2} s ({}, {:.1} mm deep)",
                    c.a,
                    c.b,
                    c.t,
                    c.during,
                    c.depth * 1e3
                ),
            });
        }
        report.collisions = self.contacts.collisions().to_vec();
        let now = self.sim.snapshot();
        let mut goals = check_goals(self.setup.task, &now, &paths);
        let speeds: Vec<(String, f64, f64)> = (0..self.sim.objects.len())
            .filter(|&i| self.sim.objects[i].movable)
            .map(|i| {
                let (v, w) = self.sim.object_speed(i);
                (self.sim.objects[i].name.clone(), v, w)
            })
            .collect();
        goals.push(check_rest(&speeds, options.rest_speed));
        for g in goals.iter().filter(|g| !g.holds) {
            report.failures.push(Failure {
                cause: Cause::GoalNotMet,
                detail: format!("{}: {}", g.goal, g.detail),
            });
        }
        report.goals = goals;
        report.simulated_seconds = self.sim.time();
    }

    fn keyframe_check(&self, plan: &Plan, k: usize, at: f64) -> KeyframeCheck {
        let kf = &self.setup.spec.keyframes[k];
        let tcp = self.tcp_at(plan, at);
        let reference = self.reference_pose(&kf.reference).unwrap_or(kf.tsr.t0_w);
        check_keyframe(kf, k, &reference, &tcp, self.sim.time())
    }
}

/// The placements of a trial: the task's nominal world, or a randomized one.
pub fn trial_world(
    task: &Task,
    randomized: bool,
    seed: u64,
) -> Result<World, akl_scene::SceneError> {
    if randomized {
        akl_scene::randomize(task, seed)
    } else {
        Ok(task.world.clone())
    }
}
