//! Tests of planning whole specs.

use super::*;
use crate::check::{recheck, RecheckOptions};
use crate::hand::PUSH_SHARE;
use crate::plan::{GripperAction, SegmentKind};
use crate::robot::PANDA_TOML;
use crate::rrt::RrtOptions;
use crate::search::plan_task;
use akl_scene::{builtin, randomize, Object};

#[test]
fn a_grasped_object_ends_centred_between_the_fingers_and_squared_on_the_pads() {
    use akl_tsr::pose::{pose_from_xyz_rpy, rotation_distance};
    let block = Shape::Box {
        size: [0.05, 0.05, 0.08],
    };
    let tcp = pose_from_xyz_rpy([0.5, 0.0, 0.1], [std::f64::consts::PI, 0.0, 0.3]);
    // Seen 0.04 rad off the hand's turn about the vertical.
    let seen = pose_from_xyz_rpy([0.503, 0.002, 0.06], [0.0, 0.0, 0.34]);
    let held = centred_in_hand(&tcp, &seen, &block);
    let plain = tcp.inverse() * seen;
    assert!(held.translation.y.abs() < 1e-12 && plain.translation.y.abs() > 1e-3);
    assert!((held.translation.z - plain.translation.z).abs() < 1e-12);
    assert!((rotation_distance(&held, &plain) - 0.04).abs() < 1e-9);
    // Square in the hand: its faces lie along the TCP axes.
    let r = held.rotation.to_rotation_matrix();
    assert!((r.matrix().column(0).x.abs() - 1.0).abs() < 1e-9);
    // A turn further than the squeeze undoes stays.
    let far = pose_from_xyz_rpy([0.503, 0.002, 0.06], [0.0, 0.0, 0.03]);
    let kept = centred_in_hand(&tcp, &far, &block);
    assert!(rotation_distance(&kept, &(tcp.inverse() * far)) < 1e-12);
}

fn options(seed: u64) -> PlanOptions {
    PlanOptions {
        seed,
        ..PlanOptions::default()
    }
}

fn plan_in(robot: &Robot, name: &str, world: &World, seed: u64) -> Result<Plan, PlanError> {
    let task = builtin::task(name).unwrap().unwrap();
    plan_task(robot, task.truth.as_ref().unwrap(), world, &options(seed))
}

fn assert_sound(robot: &Robot, world: &World, plan: &Plan) {
    let violations = recheck(robot, world, plan, &RecheckOptions::default());
    assert!(
        violations.is_empty(),
        "{} violations, first: {}",
        violations.len(),
        violations[0]
    );
}

#[test]
fn the_three_ground_truth_specs_plan_and_pass_a_dense_recheck() {
    let robot = Robot::panda().unwrap();
    for name in builtin::names() {
        let task = builtin::task(name).unwrap().unwrap();
        let plan = plan_in(&robot, name, &task.world, 1).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_sound(&robot, &task.world, &plan);
        let truth = task.truth.as_ref().unwrap();
        let grasps = truth
            .keyframes
            .windows(2)
            .filter(|w| w[0].gripper == Gripper::Open && w[1].gripper == Gripper::Closed)
            .count()
            + usize::from(truth.keyframes[0].gripper == Gripper::Closed);
        assert_eq!(plan.events.len(), 2 * grasps, "{name}");
        let lines = plan
            .segments
            .iter()
            .filter(|s| s.kind == SegmentKind::Line)
            .count();
        let required = truth.line_count();
        assert_eq!(lines, required, "{name}");
        assert!((plan.sample(plan.duration).len()) == 7);
        assert_eq!(plan.sample(0.0), robot.ready());
    }
}

#[test]
fn lines_run_between_poses_of_the_grounded_keyframes() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("inspection").unwrap().unwrap();
    let plan = plan_in(&robot, "inspection", &task.world, 3).unwrap();
    let grounded = task
        .truth
        .as_ref()
        .unwrap()
        .ground(&task.world.object_poses())
        .unwrap();
    let line = plan
        .segments
        .iter()
        .find(|s| s.kind == SegmentKind::Line)
        .unwrap();
    let poses = line.line.as_ref().unwrap();
    assert_eq!(line.keyframe, 2);
    assert!(grounded.keyframes[1].tsr.contains(&poses.from));
    assert!(grounded.keyframes[2].tsr.contains(&poses.to));
    assert_eq!(line.holding.as_deref(), Some("part"));
}

#[test]
fn the_pipe_slides_on_the_rail_and_is_placed_in_the_clamp() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("assembly").unwrap().unwrap();
    let plan = plan_in(&robot, "assembly", &task.world, 1).unwrap();
    let line = plan
        .segments
        .iter()
        .find(|s| s.kind == SegmentKind::Line)
        .unwrap();
    // The rail it slides on, and the table under the rail it is set down on.
    assert_eq!(line.allowed.held_may_touch, ["rail", "table"]);
    // The insertion: the pipe may brush the clamp it enters, nothing else.
    let mut entered = line.allowed.held_may_brush.clone();
    entered.sort();
    assert_eq!(entered, ["clamp_left", "clamp_right", "clamp_top"]);
    let release = plan.events.iter().rfind(|e| e.object == "pipe").unwrap();
    assert_eq!(release.action, GripperAction::Open);
    let goal = akl_tsr::pose::pose_from_xyz_rpy(
        [0.55, -0.23, 0.065],
        [std::f64::consts::FRAC_PI_2, 0.0, 0.0],
    );
    assert!(akl_tsr::pose::position_distance(&release.object_pose, &goal) < 0.002);
}

#[test]
fn the_same_seed_gives_the_same_plan() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("assembly").unwrap().unwrap();
    let strip = |p: Plan| -> Plan {
        let mut p = p;
        for s in &mut p.segments {
            s.planning_time = 0.0;
        }
        p
    };
    let a = strip(plan_in(&robot, "assembly", &task.world, 5).unwrap());
    let b = strip(plan_in(&robot, "assembly", &task.world, 5).unwrap());
    assert_eq!(a, b);
}

#[test]
fn a_plan_round_trips_through_json_and_samples_the_same() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let plan = plan_in(&robot, "pick_place", &task.world, 2).unwrap();
    let back = Plan::from_json(&plan.to_json().unwrap()).unwrap();
    for k in 0..50 {
        let t = plan.duration * k as f64 / 49.0;
        let (a, b) = (plan.sample(t), back.sample(t));
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12));
    }
}

#[test]
fn failures_name_the_keyframe_and_the_reason() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("inspection").unwrap().unwrap();
    let truth = task.truth.clone().unwrap();

    let mut far = truth.clone();
    far.keyframes[3].tsr.tw_e.translation.vector.x += 2.0;
    let e = plan_task(&robot, &far, &task.world, &options(1)).unwrap_err();
    assert!(
        matches!(e, PlanError::Unreachable { keyframe: 3, .. }),
        "{e}"
    );
    assert!(e.to_string().starts_with("keyframe 3: unreachable"), "{e}");

    let mut furniture = truth.clone();
    furniture.keyframes[0].reference = "table".into();
    let e = plan_task(&robot, &furniture, &task.world, &options(1)).unwrap_err();
    assert!(
        e.to_string()
            .contains("`table`, which is not a movable object"),
        "{e}"
    );

    let mut low = truth.clone();
    for k in [1, 2] {
        low.keyframes[k].tsr.tw_e.translation.vector.z = 0.0;
    }
    let e = plan_task(&robot, &low, &task.world, &options(1)).unwrap_err();
    assert!(e.to_string().contains("keyframe"), "{e}");

    let mut unknown = truth;
    unknown.keyframes[2].reference = "ghost".into();
    let e = plan_task(&robot, &unknown, &task.world, &options(1)).unwrap_err();
    assert!(e.to_string().contains("`ghost`"), "{e}");
}

fn walled(task: &akl_scene::Task) -> World {
    let mut world = task.world.clone();
    world.objects.push(Object {
        name: "wall".into(),
        shape: Shape::Box {
            size: [0.04, 0.04, 0.6],
        },
        pose: akl_tsr::pose::pose_from_xyz([0.40, 0.12, 0.3]),
        movable: false,
        mass: 0.0,
        friction: 0.5,
    });
    world
}

#[test]
fn a_wall_needs_a_search_and_a_tiny_budget_is_reported() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let world = walled(&task);
    let truth = task.truth.as_ref().unwrap();
    let plan = plan_task(&robot, truth, &world, &options(4)).unwrap();
    assert_sound(&robot, &world, &plan);
    let free = plan
        .segments
        .iter()
        .find(|s| s.kind == SegmentKind::Free)
        .unwrap();
    assert!(free.waypoints.len() > 2, "the pole should force a detour");
    let tiny = PlanOptions {
        rrt: RrtOptions {
            max_iterations: 1,
            ..RrtOptions::default()
        },
        ..options(4)
    };
    let e = plan_task(&robot, truth, &world, &tiny).unwrap_err();
    assert!(
        matches!(&e, PlanError::BudgetExhausted { segment, .. } if segment.contains("keyframe")),
        "{e}"
    );
}

#[test]
fn the_generic_solver_plans_too() {
    let robot =
        Robot::panda_with(&PANDA_TOML.replace("solver = \"panda\"", "solver = \"dls\"")).unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let plan = plan_in(&robot, "pick_place", &task.world, 1).unwrap();
    assert_sound(&robot, &task.world, &plan);
}

/// Success rate over 100 randomized worlds per task (seconds in release):
/// `cargo test -p akl-planner --release randomized_success_rate -- --ignored --nocapture`.
#[test]
#[ignore]
fn randomized_success_rate() {
    let robot = Robot::panda().unwrap();
    for name in builtin::names() {
        let task = builtin::task(name).unwrap().unwrap();
        let mut planned = 0;
        for world_seed in 0..100 {
            let world = randomize(&task, world_seed).unwrap();
            match plan_in(&robot, name, &world, world_seed) {
                Ok(plan) => {
                    assert_sound(&robot, &world, &plan);
                    planned += 1;
                }
                Err(e) => println!("{name}, world {world_seed}: {e}"),
            }
        }
        println!("{name}: {planned}/100 randomized worlds planned");
        assert!(planned >= 95, "{name}: {planned}/100");
    }
}

/// In randomized worlds of every built-in task, every ground truth plans, and every plan is
/// collision-free under a dense re-check, keeps its lines within 1 mm and stays within the
/// joint, velocity and acceleration limits (four layouts and planner seeds per task, among them
/// pick_place layout 602 with seed 0, a failure proptest once found).
#[test]
fn randomized_worlds_plan_soundly() {
    let robot = Robot::panda().unwrap();
    for name in builtin::names() {
        let task = builtin::task(name).unwrap().unwrap();
        for (world_seed, seed) in [(11, 3), (517, 40), (602, 0), (904, 771)] {
            let world = randomize(&task, world_seed).unwrap();
            let plan = plan_in(&robot, name, &world, seed)
                .unwrap_or_else(|e| panic!("{name} world {world_seed} seed {seed}: {e}"));
            let violations = recheck(&robot, &world, &plan, &RecheckOptions::default());
            assert!(violations.is_empty(), "{name}: {}", violations[0]);
        }
    }
}

/// A long cylinder tilted across the fingers is pushed to the midline where its axis passes
/// under the TCP, not where its centre lies.
#[test]
fn a_tilted_cylinder_is_centred_where_its_axis_passes_the_fingers() {
    use akl_tsr::nalgebra::{Translation3, UnitQuaternion};
    let tcp = Pose::identity();
    let tilt: f64 = 0.05;
    let dir = Vector3::new(tilt.cos(), tilt.sin(), 0.0);
    let under = Vector3::new(0.0, 0.008, 0.0);
    let centre = under + 0.1 * dir;
    let pipe = Pose::from_parts(
        Translation3::from(centre),
        UnitQuaternion::rotation_between(&Vector3::z(), &dir).unwrap(),
    );
    let cylinder = Shape::Cylinder {
        radius: 0.025,
        length: 0.3,
    };
    let offset = centring_offset(&cylinder, &pipe, &tcp);
    assert!(
        (offset - 0.008 * tilt.cos().powi(2)).abs() < 1e-12,
        "{offset}"
    );
    assert!(
        (centring_offset(&Shape::Sphere { radius: 0.02 }, &pipe, &tcp) - centre.y).abs() < 1e-12
    );
}

/// A grasp's closing lasts the fingers' travel to the object, the time they take to push it
/// from where it lies between them to their midline (at the push share of their speed), and
/// the settling pause: an off-centre block is given longer than a centred one.
#[test]
fn the_closing_waits_for_the_fingers_to_centre_the_object() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let speed = robot.finger_speed();
    let mut off_centre = 0;
    for seed in 0..4 {
        let world = randomize(&task, seed).unwrap();
        let mut sampled = options(seed);
        sampled.goals.strategy = crate::goal::GoalStrategy::Sampled;
        let plan = plan_task(&robot, task.truth.as_ref().unwrap(), &world, &sampled).unwrap();
        let mut width = robot.open_width();
        for s in &plan.segments {
            if s.kind == SegmentKind::Gripper && s.width < width {
                let event = plan
                    .events
                    .iter()
                    .find(|e| e.action == GripperAction::Close && (e.t - s.start).abs() < 1e-9)
                    .unwrap();
                let object = world.object(&event.object).unwrap();
                let tcp = world.robot_base * robot.tcp_pose(&s.waypoints[0]);
                let offset = (tcp.inverse() * object.pose).translation.y.abs();
                let push = offset * (1.0 / PUSH_SHARE - 1.0);
                let expected = (0.5 * (width - s.width) + push) / speed
                    + PlanOptions::default().gripper_settle;
                assert!(
                    ((s.end - s.start) - expected).abs() < 1e-9,
                    "{} s, expected {expected} s",
                    s.end - s.start
                );
                off_centre += usize::from(offset > 5e-4);
            }
            width = s.width;
        }
    }
    assert!(off_centre > 0, "no grasp off the block's middle");
}
