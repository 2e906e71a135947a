//! One trial: perceive the world, plan the spec on what was perceived, simulate the plan in the
//! true world, and judge what the simulation measured.

use crate::arm::Drives;
use crate::checks::keyframe::KeyframeSlack;
use crate::checks::{collision, goals, grasp, keyframe, line, release, slip};
use crate::contacts::{ContactLimits, ContactPoint};
use crate::grasp::GraspLimits;
use crate::interrupt::Interrupt;
use crate::perception::{perceive, PoseNoise};
use crate::report::{rank, Cause, Failure, Tracking, TrialReport};
use crate::settle::check_settles;
use crate::simulate::simulate;
use crate::world::Physics;
use akl_planner::{plan_task, Plan, PlanError, PlanOptions, Robot};
use akl_scene::{Task, World};
use akl_tsr::{Pose, PoseJson, TaskSpec};
use std::collections::BTreeMap;
use std::time::Instant;

/// Settings of execution.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecOptions {
    /// Simulation settings.
    pub physics: Physics,
    /// Planner settings (the seed is replaced by each trial's).
    pub plan: PlanOptions,
    /// The simulated joint servos and gripper.
    pub drives: Drives,
    /// What counts as a sound grasp.
    pub grasp: GraspLimits,
    /// How deep and hard contacts may be.
    pub contacts: ContactLimits,
    /// Perception error of the movable objects' poses.
    pub noise: PoseNoise,
    /// How far the TCP may leave a `move_in_line` segment's line (metres).
    pub line_tolerance: f64,
    /// How far a held object may move in the hand (metres).
    pub slip_limit: f64,
    /// How far a released object may fall (metres).
    pub drop_limit: f64,
    /// Simulated seconds of settling after the plan, before the goals are checked.
    pub settle: f64,
    /// Longest settling (simulated seconds after the plan): past `settle`, the simulation goes
    /// on while an object still moves faster than `rest_speed`, up to this. A part that rocks
    /// for a moment in a clamp is then judged at rest, as a person would wait for it, while an
    /// object that never comes to rest still fails the rest check.
    pub settle_max: f64,
    /// Speed below which an object counts as at rest (m/s; ten times that in rad/s).
    pub rest_speed: f64,
    /// Samples per simulated second of the objects' paths.
    pub path_rate: f64,
    /// Raised to stop part-way (Ctrl-C): once it is, batches start no more trials (see
    /// [`crate::interrupt`]). Never raised by default. Not a setting of the trials themselves:
    /// it changes which trials run, never what one of them gives.
    pub interrupt: Interrupt,
}

impl Default for ExecOptions {
    fn default() -> Self {
        ExecOptions {
            physics: Physics::default(),
            plan: PlanOptions::default(),
            drives: Drives::default(),
            grasp: GraspLimits::default(),
            contacts: ContactLimits::default(),
            noise: PoseNoise::default(),
            line_tolerance: 0.005,
            slip_limit: 0.005,
            drop_limit: 0.02,
            settle: 0.5,
            settle_max: 2.0,
            rest_speed: 0.01,
            path_rate: 240.0,
            interrupt: Interrupt::NEVER,
        }
    }
}

impl ExecOptions {
    /// The slack of the keyframe check: the simulation's plus four standard deviations of
    /// the perception error.
    pub fn keyframe_slack(&self) -> KeyframeSlack {
        KeyframeSlack::with_perception(self.noise.position, self.noise.yaw)
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

/// One instant of a simulation, for a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Simulated time (seconds).
    pub t: f64,
    /// World pose of every robot link, in the robot's link order.
    pub links: Vec<Pose>,
    /// World pose of every object, in the task's order.
    pub objects: Vec<Pose>,
    /// The simulated arm joint positions.
    pub joints: Vec<f64>,
    /// The simulated gripper opening (metres).
    pub width: f64,
    /// Contacts of the arm and the held object since the previous frame.
    pub contacts: Vec<ContactPoint>,
}

/// A trial as a trace shows it: the worlds, the plan, and the simulation's frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Frames per simulated second.
    pub rate: f64,
    /// The frames, in time order (none when planning failed).
    pub frames: Vec<Frame>,
    /// The plan executed, when there was one.
    pub plan: Option<Plan>,
    /// The world the planner perceived.
    pub perceived: Option<World>,
    /// Why planning failed, when it did.
    pub planning_failure: Option<String>,
}

impl Timeline {
    /// An empty timeline recording `rate` frames per simulated second.
    pub fn new(rate: f64) -> Timeline {
        Timeline {
            rate,
            frames: Vec::new(),
            plan: None,
            perceived: None,
            planning_failure: None,
        }
    }
}

/// The cause a planning error counts under.
pub fn plan_cause(e: &PlanError) -> Cause {
    match e {
        PlanError::Unreachable { .. } => Cause::Unreachable,
        PlanError::NoCollisionFreeIk { .. } => Cause::NoCollisionFreeGoal,
        _ => Cause::NoPlan,
    }
}

fn poses_of<'w>(
    world: &'w World,
    names: impl Iterator<Item = &'w str>,
) -> BTreeMap<String, PoseJson> {
    names
        .filter_map(|n| world.object(n))
        .map(|o| (o.name.clone(), PoseJson::from_pose(&o.pose)))
        .collect()
}

/// Runs trial `trial` in `world` (the true placements): perceives it with the trial's
/// `seed`, plans on what was perceived with the same seed, simulates in `world`, and judges.
/// Its failures come in the order they occurred, the first its root cause ([`rank`]). Records
/// the simulation into `timeline` when given.
pub fn run_trial(
    setup: &Setup,
    trial: usize,
    seed: u64,
    world: &World,
    mut timeline: Option<&mut Timeline>,
) -> TrialReport {
    let options = setup.options;
    let perceived = perceive(world, &options.noise, seed);
    let motion = setup.task.motion().ok();
    let watched = world
        .objects
        .iter()
        .filter(|o| o.movable || motion.as_ref().is_some_and(|m| m.moves(&o.name)))
        .map(|o| o.name.as_str());
    let movable = world
        .objects
        .iter()
        .filter(|o| o.movable)
        .map(|o| o.name.as_str());
    let mut report = TrialReport {
        trial,
        seed,
        passed: false,
        failures: Vec::new(),
        placements: poses_of(world, watched),
        perceived: poses_of(&perceived, movable),
        plan_seconds: 0.0,
        sim_seconds: 0.0,
        simulated_seconds: 0.0,
        keyframes: Vec::new(),
        lines: Vec::new(),
        grasps: Vec::new(),
        releases: Vec::new(),
        collisions: Vec::new(),
        deepest_contact: Default::default(),
        largest_force: Default::default(),
        tracking: Tracking::default(),
        goals: Vec::new(),
    };
    let plan_options = PlanOptions {
        seed,
        ..options.plan.clone()
    };
    let started = Instant::now();
    let planned = plan_task(setup.robot, setup.spec, &perceived, &plan_options);
    report.plan_seconds = started.elapsed().as_secs_f64();
    if let Some(tl) = timeline.as_deref_mut() {
        tl.perceived = Some(perceived.clone());
    }
    match planned {
        Ok(plan) => {
            let started = Instant::now();
            match simulate(setup, world, &plan, timeline) {
                Some(obs) => judge(setup, &obs, &mut report),
                None => report.failures.push(
                    Failure::new(
                        Cause::NoPlan,
                        "the robot's gripper cannot be simulated (it needs two prismatic fingers on one link)",
                    )
                    .at_time(0.0),
                ),
            }
            report.sim_seconds = started.elapsed().as_secs_f64();
        }
        Err(e) => {
            if let Some(tl) = timeline {
                tl.planning_failure = Some(e.to_string());
            }
            report.failures.push(
                Failure::new(plan_cause(&e), e.to_string())
                    .at(e.keyframe())
                    .at_time(0.0),
            );
        }
    }
    rank(&mut report.failures);
    report.passed = report.failures.is_empty();
    report
}

/// Turns what the simulation measured into the report's checks and failures.
fn judge(setup: &Setup, obs: &crate::simulate::Observations, report: &mut TrialReport) {
    let options = setup.options;
    let (grasps, mut failures) = grasp::check(&obs.grasps);
    failures.extend(slip::check(&obs.grasps, options.slip_limit));
    let (releases, dropped) = release::check(
        &obs.releases,
        &obs.still_held,
        options.drop_limit,
        obs.simulated,
    );
    failures.extend(dropped);
    failures.extend(collision::check(obs.contacts.collisions()));
    let (keyframes, missed) = keyframe::check(setup.spec, &obs.reaches, &options.keyframe_slack());
    failures.extend(missed);
    let (lines, strayed) = line::check(&obs.lines, options.line_tolerance);
    failures.extend(strayed);
    let (goals, unmet) = goals::check(setup.task, obs, options.rest_speed);
    failures.extend(unmet);
    report.failures.extend(failures);
    report.keyframes = keyframes;
    report.lines = lines;
    report.grasps = grasps;
    report.releases = releases;
    report.collisions = obs.contacts.collisions().to_vec();
    report.deepest_contact = obs.contacts.deepest.clone();
    report.largest_force = obs.contacts.strongest.clone();
    report.tracking = Tracking {
        max: obs.tracking_max,
        rms: obs.tracking_rms,
    };
    report.goals = goals;
    report.simulated_seconds = obs.simulated;
}

/// The placements of a trial: the task's nominal world, or a randomized one that stands still
/// when simulated untouched with `physics` ([`crate::settle::check_settles`]; a layout that
/// does not is redrawn like an infeasible one).
pub fn trial_world(
    task: &Task,
    randomized: bool,
    seed: u64,
    physics: &Physics,
) -> Result<World, akl_scene::SceneError> {
    if randomized {
        let settles = |w: &World| check_settles(w, physics).map_err(|e| e.to_string());
        akl_scene::randomize_layout_with(task, seed, &settles).map(|l| l.world)
    } else {
        Ok(task.world.clone())
    }
}
