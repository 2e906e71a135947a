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
use akl_planner::{plan_best, PlanError, PlanOptions};
use akl_scene::{Task, World};
use akl_tsr::PoseJson;
use std::collections::BTreeMap;
use std::time::Instant;

/// The cause a planning error counts under.
pub(crate) fn plan_cause(e: &PlanError) -> Cause {
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
/// Its failures come in the order they occurred, the first its root cause. Records
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
        plan_probes: 0,
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
    let planned = plan_best(setup.robot, setup.spec, &perceived, &plan_options).map(|best| {
        report.plan_probes = best.probes;
        best.plan
    });
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
                        "the robot's gripper cannot be simulated (it needs two prismatic fingers on one link, or a knuckle whose mimic joints move two fingertips)",
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::ExecOptions;
    use akl_planner::Robot;
    use akl_tsr::TaskSpec;

    fn run(task: &Task, spec: &TaskSpec, world: &World) -> TrialReport {
        run_with(task, spec, world, &ExecOptions::default(), 11)
    }

    fn run_with(
        task: &Task,
        spec: &TaskSpec,
        world: &World,
        options: &ExecOptions,
        seed: u64,
    ) -> TrialReport {
        let robot = Robot::panda().unwrap();
        let setup = Setup {
            robot: &robot,
            task,
            spec,
            options,
        };
        run_trial(&setup, 4, seed, world, None)
    }

    /// The ground truth on the nominal world passes, every keyframe reached and every check
    /// recorded, with the objects placed and perceived where they were.
    #[test]
    fn the_truth_passes_with_every_check_recorded() {
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let r = run(&task, &spec, &task.world);
        assert!(r.passed && r.failures.is_empty(), "{:?}", r.failures);
        assert_eq!((r.trial, r.seed), (4, 11));
        assert_eq!(r.keyframes.len(), spec.keyframes.len());
        assert!(r.keyframes.iter().all(|k| k.reached));
        assert_eq!(r.grasps.len(), 2);
        assert!(r.goals.iter().all(|g| g.holds) && !r.goals.is_empty());
        for name in ["block_a", "block_b"] {
            let placed = r.placements[name].to_pose().unwrap();
            let seen = r.perceived[name].to_pose().unwrap();
            assert_eq!(placed, task.world.object(name).unwrap().pose);
            // Perceived with noise, but near.
            let off = (placed.translation.vector - seen.translation.vector).norm();
            assert!(off > 0.0 && off < 0.02, "{name} perceived {off} m off");
        }
        assert!(r.simulated_seconds > 0.0);
    }

    /// The truth planned on a world perceived 3 cm off (seed 8): the arm knocks block_a
    /// before it closes beside it. The checks run grasps before collisions, but the failures
    /// come in the order they occurred: the collision first and the only root, the missed
    /// grasp after it, the unmet goals at the end of settling last.
    #[test]
    fn failures_come_in_the_order_they_occurred_the_first_the_root() {
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let mut options = ExecOptions::default();
        options.noise.position = 0.03;
        let r = run_with(&task, &spec, &task.world, &options, 8);
        assert!(!r.passed);
        let f = &r.failures;
        assert!(f[0].root && f[1..].iter().all(|f| !f.root), "{f:?}");
        let times: Vec<f64> = f.iter().map(|f| f.t.unwrap()).collect();
        assert!(times.windows(2).all(|w| w[0] <= w[1]), "{times:?}");
        assert_eq!((f[0].cause, f[0].keyframe), (Cause::Collision, Some(0)));
        let grasp = f
            .iter()
            .position(|f| f.cause == Cause::GraspFailed && f.keyframe == Some(0))
            .expect("the grasp missed");
        assert!(grasp > 0 && times[grasp] > times[0]);
        let last = f.last().unwrap();
        assert_eq!(last.cause, Cause::GoalNotMet);
        assert_eq!(last.t, Some(r.simulated_seconds));
    }

    /// A spec that cannot be planned (inspection's part put 3 cm into the shelf): one failure,
    /// at time 0, naming the keyframe, and nothing simulated.
    #[test]
    fn a_planning_failure_is_the_only_failure_at_time_zero() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let mut spec = task.truth.clone().unwrap();
        let last = spec.keyframes.len() - 1;
        spec.keyframes[last].tsr.tw_e.translation.vector.z -= 0.03;
        let r = run(&task, &spec, &task.world);
        assert!(!r.passed);
        assert_eq!(r.failures.len(), 1, "{:?}", r.failures);
        let f = &r.failures[0];
        assert_eq!((f.keyframe, f.t, f.root), (Some(last), Some(0.0), true));
        assert!(matches!(
            f.cause,
            Cause::NoCollisionFreeGoal | Cause::Unreachable | Cause::NoPlan
        ));
        assert!(
            f.detail.contains(&format!("keyframe {last}")),
            "{}",
            f.detail
        );
        assert_eq!(r.simulated_seconds, 0.0);
        assert!(r.keyframes.is_empty() && r.grasps.is_empty());
    }
}
