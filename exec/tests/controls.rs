//! Negative controls: specs built wrong from the ground truths, each of which the verification
//! must reject in at least 9 of 10 randomized trials for the named cause (and so the deployment
//! gate fails it), beside the ground truths, which must pass the same trials.

use akl_exec::batch::{Batch, BatchOptions};
use akl_exec::report::{BatchReport, Cause};
use akl_exec::{Drives, ExecOptions};
use akl_planner::Robot;
use akl_scene::{builtin, Task};
use akl_stats::{Decision, Gate, GateOptions};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Gripper, TaskSpec};

const TRIALS: usize = 10;

fn task(name: &str) -> Task {
    builtin::task(name).unwrap().unwrap()
}

fn run_with(task: &Task, spec: &TaskSpec, exec: &ExecOptions) -> BatchReport {
    let robot = Robot::panda().unwrap();
    let options = BatchOptions {
        trials: TRIALS,
        randomize: true,
        seed: 100,
        jobs: 2,
    };
    Batch::new(&robot, task, spec, exec, options)
        .unwrap()
        .run(&|_| {})
        .unwrap()
}

fn run(task: &Task, spec: &TaskSpec) -> BatchReport {
    run_with(task, spec, &ExecOptions::default())
}

/// At least 9 of the trials fail for `cause`, the first such failure says `says`, and the
/// deployment gate (its defaults, the trials judged in seed order) fails the spec.
fn rejected_for(report: &BatchReport, cause: Cause, says: &str) {
    let gate = Gate::new(GateOptions::default()).unwrap();
    let mut in_order: Vec<_> = report.reports.iter().collect();
    in_order.sort_by_key(|r| r.seed);
    let judged = gate.judge(in_order.iter().map(|r| r.passed));
    assert!(
        matches!(judged, Some((Decision::Fails, _))),
        "the gate: {judged:?}"
    );
    let failing: Vec<_> = report
        .reports
        .iter()
        .filter(|r| r.failures.iter().any(|f| f.cause == cause))
        .collect();
    println!(
        "{}: {} of {} trials fail for {cause}",
        report.method,
        failing.len(),
        report.trials
    );
    assert!(
        failing.len() >= 9,
        "only {} of {} trials failed for {cause}: {:?}",
        failing.len(),
        report.trials,
        report.failures
    );
    let detail = &failing[0]
        .failures
        .iter()
        .find(|f| f.cause == cause)
        .unwrap()
        .detail;
    assert!(detail.contains(says), "{detail}");
}

/// Moves keyframe `k`'s target by `offset` in its reference object's frame.
fn shifted(spec: &TaskSpec, k: usize, offset: [f64; 3]) -> TaskSpec {
    let mut wrong = spec.clone();
    wrong.keyframes[k].tsr.tw_e.translation.vector += Vector3::from(offset);
    wrong
}

#[test]
fn the_ground_truths_pass_the_trials_the_controls_fail() {
    for name in builtin::names() {
        let t = task(name);
        let report = run(&t, t.truth.as_ref().unwrap());
        assert!(report.all_passed(), "{name}: {:?}", report.failures);
    }
}

/// A grasp 3.75 cm off-centre on the 5 cm part: one finger comes down on the part's top.
#[test]
fn an_off_centre_grasp_puts_a_finger_into_the_part() {
    let t = task("inspection");
    let wrong = shifted(t.truth.as_ref().unwrap(), 0, [0.0, 0.0375, 0.0]);
    rejected_for(
        &run(&t, &wrong),
        Cause::Collision,
        "finger pressed against part",
    );
}

/// Root cause first, on real trials: with the off-centre grasp the finger comes down on the
/// part during the approach (a collision, about 0.85 s), the pads then close on it badly (a
/// failed grasp, about 1.3 s) and the part ends nowhere near its goals (judged after
/// settling). The checks list grasps before collisions and goals last; in time order the
/// collision is the root cause, the failed grasp and the unmet goals secondary. The batch
/// counts each failed trial once, by its root cause.
#[test]
fn a_trials_earliest_failure_is_its_root_cause() {
    let t = task("inspection");
    let wrong = shifted(t.truth.as_ref().unwrap(), 0, [0.0, 0.0375, 0.0]);
    let report = run(&t, &wrong);
    let mut both = 0;
    for r in report.reports.iter().filter(|r| !r.passed) {
        let times: Vec<f64> = r.failures.iter().map(|f| f.t.unwrap()).collect();
        assert!(times.windows(2).all(|w| w[0] <= w[1]), "{times:?}");
        let roots: Vec<bool> = r.failures.iter().map(|f| f.root).collect();
        assert!(roots[0] && !roots[1..].contains(&true), "{roots:?}");
        let at = |cause: Cause| r.failures.iter().find(|f| f.cause == cause).map(|f| f.t);
        if let (Some(collided), Some(unmet)) = (at(Cause::Collision), at(Cause::GoalNotMet)) {
            assert!(collided < unmet, "{:?}", r.failures);
            assert_eq!(r.failures[0].cause, Cause::Collision, "{:?}", r.failures);
            both += 1;
        }
    }
    assert!(both >= 5, "{both} trials failed for a collision and a goal");
    let failed = report.trials - report.passed;
    assert_eq!(report.failures.values().sum::<usize>(), failed);
    assert_eq!(report.failures.get(&Cause::Collision), Some(&failed));
    assert!(
        report.secondary[&Cause::GoalNotMet] >= both,
        "{:?}",
        report.secondary
    );
    assert!(
        report.secondary.contains_key(&Cause::GraspFailed),
        "{:?}",
        report.secondary
    );
}

/// Fingertips 1 mm below the top edge: the pads hold a 1 mm strip of the part.
#[test]
fn fingertips_on_the_edge_are_no_grasp() {
    let t = task("inspection");
    // The truth's TCP is 2 cm above the part's centre, 3 cm below its top; the pads (Franka's
    // rubber tips) reach 9.5 mm beyond the TCP. Raise the grasp so the fingertips end 1 mm
    // below the top, and every later keyframe by as much, so that only the grasp is wrong.
    let mut wrong = t.truth.clone().unwrap();
    for k in 0..wrong.keyframes.len() {
        wrong = shifted(&wrong, k, [0.0, 0.0, 0.0385]);
    }
    rejected_for(&run(&t, &wrong), Cause::GraspFailed, "not held soundly");
}

/// The last keyframe keeps the gripper closed: the part is carried to the shelf and never let go.
#[test]
fn a_part_never_released_fails_its_goal() {
    let t = task("inspection");
    let mut wrong = t.truth.clone().unwrap();
    wrong.keyframes.last_mut().unwrap().gripper = Gripper::Closed;
    rejected_for(&run(&t, &wrong), Cause::GoalNotMet, "never releases");
}

/// The release 6 cm above the shelf: the part falls.
#[test]
fn a_release_six_centimetres_up_drops_the_part() {
    let t = task("inspection");
    let last = t.truth.as_ref().unwrap().keyframes.len() - 1;
    // The TCP's z axis points down: a smaller z in the shelf's frame is higher.
    let wrong = shifted(t.truth.as_ref().unwrap(), last, [0.0, 0.0, 0.06]);
    rejected_for(&run(&t, &wrong), Cause::Dropped, "fell");
}

/// A placement 3 cm into the shelf: the planner, which knows the held object may rest on its
/// support but not press into it, finds no pose of the keyframe that does not.
#[test]
fn a_placement_pressed_into_the_shelf_is_refused() {
    let t = task("pick_place");
    let wrong = shifted(t.truth.as_ref().unwrap(), 1, [0.0, 0.0, -0.03]);
    rejected_for(
        &run(&t, &wrong),
        Cause::NoCollisionFreeGoal,
        "held block_a with shelf_2",
    );
}

/// The first grasp aimed at where block_b stands, grounded on block_a: the hand closes on
/// (or comes down on) block_b, which the step does not grasp. Refused in planning when the
/// perceived block_b is in the way, in the simulation when the pads close on it.
#[test]
fn a_grasp_of_the_wrong_object_fails() {
    let t = task("pick_place");
    let truth = t.truth.clone().unwrap();
    let mut wrong = truth.clone();
    let a = t.world.object("block_a").unwrap().pose;
    let b = t.world.object("block_b").unwrap().pose;
    wrong.keyframes[0].tsr.tw_e = a.inverse() * b * truth.keyframes[2].tsr.tw_e;
    let report = run(&t, &wrong);
    let refused = report
        .reports
        .iter()
        .filter(|r| {
            r.failures.iter().any(|f| {
                (f.cause == Cause::NoCollisionFreeGoal && f.detail.contains("with block_b"))
                    || (f.cause == Cause::GraspFailed && f.detail.starts_with("keyframe 0"))
            })
        })
        .count();
    assert!(refused >= 9, "{refused} refused: {:?}", report.failures);
}

/// Motors too weak to follow the plan: the simulated TCP lags, and the keyframes and lines
/// measured on it fail (the checks read the simulated arm, not the plan): every trial fails,
/// most of them for a keyframe or a line.
#[test]
fn motors_too_weak_to_track_miss_keyframes_and_lines() {
    let t = task("inspection");
    let weak = ExecOptions {
        drives: Drives {
            frequency: 1.5,
            ..Drives::default()
        },
        ..ExecOptions::default()
    };
    let report = run_with(&t, t.truth.as_ref().unwrap(), &weak);
    let lagging = report
        .reports
        .iter()
        .filter(|r| {
            r.failures
                .iter()
                .any(|f| matches!(f.cause, Cause::LineDeviation | Cause::KeyframeMissed))
        })
        .count();
    // The other trials' lagging arm hit something, or closed on nothing, first.
    assert!(
        report.passed == 0 && lagging >= 8,
        "{lagging}: {:?}",
        report.failures
    );
    let strays =
        report.reports.iter().flat_map(|r| &r.failures).any(|f| {
            f.cause == Cause::LineDeviation && f.detail.contains("the simulated TCP strays")
        });
    assert!(strays, "{:?}", report.failures);
}

/// The thesis' example of a badly chosen reference object (§3.2.4): block_a's placement
/// grounded on block_b instead of on its mat. The blocks start on another shelf than the mats
/// stand on, so block_a is set down beside its mat (or over the shelf's edge, and falls).
#[test]
fn a_placement_grounded_on_a_nearby_block_fails_once_the_blocks_move() {
    let t = task("pick_place");
    let mut wrong = t.truth.clone().unwrap();
    let block_b = t.world.object("block_b").unwrap().pose;
    let kf = &mut wrong.keyframes[1];
    assert_eq!(kf.reference, "mat_a");
    kf.tsr.tw_e = block_b.inverse() * kf.tsr.t0_w * kf.tsr.tw_e;
    kf.tsr.t0_w = block_b;
    kf.reference = "block_b".into();
    let report = run(&t, &wrong);
    assert!(
        report.trials - report.passed >= 9,
        "{} passed: {:?}",
        report.passed,
        report.failures
    );
    // The goal fails, as the root cause or after one (a drop, a collision on the way).
    assert!(
        report.failures.contains_key(&Cause::GoalNotMet)
            || report.secondary.contains_key(&Cause::GoalNotMet),
        "{:?} {:?}",
        report.failures,
        report.secondary
    );
}

/// Without its move_in_line constraint the pipe can only be brought down onto the rail from
/// above, through the clamp: no way to reach the release is free.
#[test]
fn the_assembly_without_its_line_makes_the_pipe_hit_the_clamp() {
    let t = task("assembly");
    let mut free = t.truth.clone().unwrap();
    let last = free.keyframes.len() - 1;
    free.keyframes[last].constraint = akl_tsr::Constraint::None;
    rejected_for(&run(&t, &free), Cause::NoCollisionFreeGoal, "keyframe 3");
}

/// Only the simulation can find this one: the planner perceived shelf_2 where the task file has
/// it, but it truly stands 2 cm higher (with the mats on it), so the placement pushes block_a
/// into its mat: harder than the contact limit, or until the grasp gives way and the block
/// slides in the hand.
#[test]
fn a_support_higher_than_perceived_is_pressed_into_in_the_simulation() {
    use akl_exec::{simulate, Setup};
    use akl_tsr::nalgebra::Translation3;
    let robot = Robot::panda().unwrap();
    let t = task("pick_place");
    let spec = t.truth.clone().unwrap();
    let exec = ExecOptions::default();
    let plan = akl_planner::plan_task(&robot, &spec, &t.world, &exec.plan).unwrap();
    let mut truth = t.world.clone();
    for name in ["shelf_2", "mat_a", "mat_b"] {
        let o = truth.object_mut(name).unwrap();
        o.pose = Translation3::new(0.0, 0.0, 0.02) * o.pose;
    }
    let setup = Setup {
        robot: &robot,
        task: &t,
        spec: &spec,
        options: &exec,
    };
    let obs = simulate(&setup, &truth, &plan, None).unwrap();
    let pressed = obs.contacts.collisions().iter().any(|c| {
        c.a == "held block_a" && c.b == "mat_a" && c.allowed && c.force > exec.contacts.max_force
    });
    let gave_way = obs.grasps[0].broke_at.is_some() && obs.grasps[0].slip > exec.slip_limit;
    assert!(
        pressed || gave_way,
        "{:?} {:?}",
        obs.contacts.collisions(),
        obs.grasps[0]
    );
    let nominal = simulate(&setup, &t.world, &plan, None).unwrap();
    assert!(
        nominal.contacts.collisions().is_empty(),
        "{:?}",
        nominal.contacts.collisions()
    );
    assert!(
        nominal.grasps[0].slip < exec.slip_limit,
        "{:?}",
        nominal.grasps[0]
    );
}

/// What became of the pipe's insertion as planned on the clamp where the task file has it,
/// executed with the clamp (walls and roof, not the rail) truly standing `offset` metres to
/// the side of the tunnel's axis: whether it was a jam (the held pipe pressed into the clamp
/// deeper or harder than a compliant insertion may, or the grasp gave way and the pipe slid
/// in the hand), and what happened, for the message.
fn insertion_into_a_clamp_moved_by(offset: f64) -> (bool, String) {
    use akl_exec::{simulate, Setup};
    use akl_tsr::nalgebra::Translation3;
    let robot = Robot::panda().unwrap();
    let t = task("assembly");
    let spec = t.truth.clone().unwrap();
    let exec = ExecOptions::default();
    let plan = akl_planner::plan_task(&robot, &spec, &t.world, &exec.plan).unwrap();
    let mut truth = t.world.clone();
    for name in ["clamp_left", "clamp_right", "clamp_top"] {
        let o = truth.object_mut(name).unwrap();
        o.pose = Translation3::new(offset, 0.0, 0.0) * o.pose;
    }
    let setup = Setup {
        robot: &robot,
        task: &t,
        spec: &spec,
        options: &exec,
    };
    let obs = simulate(&setup, &truth, &plan, None).unwrap();
    let limits = &exec.contacts;
    let pressed = obs.contacts.collisions().iter().any(|c| {
        c.a == "held pipe"
            && c.b.starts_with("clamp")
            && (c.depth > limits.max_brush_depth || c.force > limits.max_brush_force)
    });
    let pipe = &obs.grasps[1];
    let gave_way = pipe.broke_at.is_some() && pipe.slip > exec.slip_limit;
    let seen = format!("{:?} {:?}", obs.contacts.collisions(), pipe);
    (pressed || gave_way, seen)
}

/// A jam still fails although an insertion may brush its fixture. The tunnel leaves 6 mm
/// either side of the pipe, so a line 4 mm off its axis goes through; 8 mm off, the pipe's end
/// runs into a wall's face 2 mm deep, and the impact (about 170 N) breaks the grasp and slides
/// the pipe in the hand. The planner cannot see this (it plans on the clamp where it was
/// perceived); only the simulation can.
#[test]
fn an_insertion_off_the_tunnels_axis_jams_beyond_its_clearance() {
    let (jam, seen) = insertion_into_a_clamp_moved_by(0.004);
    assert!(!jam, "within the clearance: {seen}");
    let (jam, seen) = insertion_into_a_clamp_moved_by(0.008);
    assert!(jam, "into a wall: {seen}");
}

/// Inspection with no pass over the scanners (grasp, then straight to the shelf): the part
/// never crosses the row.
#[test]
fn inspection_without_the_scan_fails_its_goal() {
    let t = task("inspection");
    let mut wrong = t.truth.clone().unwrap();
    wrong.keyframes.drain(1..3);
    rejected_for(&run(&t, &wrong), Cause::GoalNotMet, "scan(part");
}

/// Inspection with the scan's `move_in_line` removed: the part is carried between the line's
/// ends by a free motion, which does not pass over the row in a straight line.
#[test]
fn inspection_without_its_line_fails_its_goal() {
    let t = task("inspection");
    let mut wrong = t.truth.clone().unwrap();
    wrong.keyframes[2].constraint = akl_tsr::Constraint::None;
    rejected_for(&run(&t, &wrong), Cause::GoalNotMet, "scan(part");
}

/// A positive control: a via-point on the world whose spec stores its frame away from the
/// world's origin is judged in that frame, where the planner puts it.
#[test]
fn a_world_keyframe_is_judged_in_its_stored_frame() {
    let t = task("pick_place");
    let mut spec = t.truth.clone().unwrap();
    let mut via = spec.keyframes[0].clone();
    via.kind = akl_tsr::KeyframeKind::Constraint;
    via.reference = akl_tsr::WORLD_FRAME.into();
    via.tsr.t0_w = akl_tsr::pose::pose_from_xyz([0.32, 0.0, 0.0]);
    via.tsr.tw_e = akl_tsr::Pose::from_parts(
        akl_tsr::nalgebra::Translation3::new(0.0, 0.0, 0.33),
        spec.keyframes[0].tsr.tw_e.rotation,
    );
    spec.keyframes.insert(1, via);
    let report = run(&t, &spec);
    assert_eq!(report.passed, report.trials, "{:?}", report.failures);
}
