//! One trial: perceive the world, plan the spec on what was perceived, simulate the plan in the
//! true world, and judge what the simulation measured.

use crate::checks::{collision, goals, grasp, keyframe, line, release, slip};
use crate::options::Setup;
use crate::perception::perceive;
use crate::report::{rank, Cause, Failure, Tracking, TrialReport};
use crate::settle::check_settles;
use crate::simulate::simulate;
use crate::timeline::Timeline;
use crate::world::Physics;
use akl_planner::{plan_task, PlanError, PlanOptions};
use akl_scene::{Task, World};
use akl_tsr::PoseJson;
use std::collections::BTreeMap;
use std::time::Instant;

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
                tl.planning_failure = Some(e.clone());
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
    let (keyframes, missed) = keyframe::check(
        setup.spec,
        &obs.reaches,
        &keyframe::KeyframeSlack::of(options),
    );
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
