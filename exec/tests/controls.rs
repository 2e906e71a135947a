//! Negative controls: specs that are wrong in a way the verification must catch, each next
//! to the correct spec on the same trials.

use akl_exec::batch::{Batch, BatchOptions};
use akl_exec::report::{BatchReport, Cause};
use akl_exec::trial::ExecOptions;
use akl_planner::Robot;
use akl_scene::{builtin, Task};
use akl_tsr::{Constraint, TaskSpec};

fn task(name: &str) -> Task {
    builtin::task(name).unwrap().unwrap()
}

fn run(robot: &Robot, task: &Task, spec: &TaskSpec, trials: usize, randomize: bool) -> BatchReport {
    let exec = ExecOptions::default();
    let options = BatchOptions {
        trials,
        randomize,
        seed: 0,
        jobs: 2,
    };
    Batch::new(robot, task, spec, &exec, options)
        .unwrap()
        .run(&|_| {})
        .unwrap()
}

fn causes(report: &BatchReport) -> Vec<Cause> {
    report.failures.keys().copied().collect()
}

/// The thesis' example of a badly chosen reference object (§3.2.4): block_a's placement on
/// shelf_2 grounded on block_b, the object nearest the hand, instead of on shelf_2. With the
/// objects where the demonstration had them the target is the same; once they move it is not.
#[test]
fn a_placement_grounded_on_a_nearby_block_fails_once_the_blocks_move() {
    let robot = Robot::panda().unwrap();
    let task = task("pick_place");
    let truth = task.truth.clone().unwrap();
    let mut wrong = truth.clone();
    let block_b = task.world.object("block_b").unwrap().pose;
    let kf = &mut wrong.keyframes[1];
    assert_eq!(kf.reference, "shelf_2");
    kf.tsr.tw_e = block_b.inverse() * kf.tsr.t0_w * kf.tsr.tw_e;
    kf.tsr.t0_w = block_b;
    kf.reference = "block_b".into();

    let nominal = run(&robot, &task, &wrong, 1, false);
    assert!(nominal.all_passed(), "{:?}", nominal.reports[0].failures);
    let right = run(&robot, &task, &truth, 6, true);
    assert!(right.all_passed(), "{:?}", right.failures);
    let moved = run(&robot, &task, &wrong, 6, true);
    assert!(
        moved.passed <= 4,
        "only {} of 6 trials failed",
        moved.trials - moved.passed
    );
    let expected = [Cause::Collision, Cause::GoalNotMet, Cause::Unreachable];
    assert!(
        causes(&moved).iter().all(|c| expected.contains(c)),
        "{:?}",
        moved.failures
    );
}

/// Without its move_in_line constraint the pipe can only be brought down onto the rail from
/// above, through the clamp: every way to reach the release collides, and the trial fails for
/// a collision of the held pipe with the clamp.
#[test]
fn the_assembly_without_its_line_makes_the_pipe_hit_the_clamp() {
    let robot = Robot::panda().unwrap();
    let task = task("assembly");
    let mut free = task.truth.clone().unwrap();
    let last = free.keyframes.len() - 1;
    assert_eq!(free.keyframes[last].constraint, Constraint::MoveInLine);
    free.keyframes[last].constraint = Constraint::None;
    let report = run(&robot, &task, &free, 2, true);
    assert_eq!(report.passed, 0);
    assert_eq!(causes(&report), vec![Cause::Collision]);
    for r in &report.reports {
        let detail = &r.failures[0].detail;
        assert!(
            detail.contains("keyframe 3") && detail.contains("held pipe with clamp_top"),
            "{detail}"
        );
    }
}

/// A keyframe 1.5 m further from its reference than the truth puts it is out of the arm's
/// reach: the trial fails as unreachable, naming the keyframe.
#[test]
fn a_keyframe_out_of_reach_is_unreachable() {
    let robot = Robot::panda().unwrap();
    let task = task("inspection");
    let mut far = task.truth.clone().unwrap();
    far.keyframes[1].tsr.tw_e.translation.vector.x += 1.5;
    let report = run(&robot, &task, &far, 2, true);
    assert_eq!(report.passed, 0);
    assert_eq!(causes(&report), vec![Cause::Unreachable]);
    assert!(report.reports[0].failures[0]
        .detail
        .starts_with("keyframe 1: unreachable"));
}
