//! Tests of the stock-URDF quirks a robot folder must accept or refuse clearly, on a small
//! six-joint arm made of primitives, laid out as vendors' xacro output is: an extra root link
//! before the arm, `<axis xyz="0 0 0"/>` on fixed joints, continuous joints, and a finger that
//! mimics the other.

use super::*;
use crate::error::GripperError;
use crate::fk::CONTINUOUS_RANGE;
use crate::Geometry;
use akl_tsr::nalgebra::Point3;

/// A six-joint arm: joints 1 and 6 continuous, a root link `world` before `base_link`, fixed
/// joints with a zero axis, and a two-finger hand whose right finger mimics the left.
pub(crate) const ARM: &str = r#"<?xml version="1.0"?>
<robot name="arm6">
  <link name="world"/>
  <joint name="world_joint" type="fixed"><parent link="world"/><child link="base_link"/>
    <origin xyz="0 0 0.02" rpy="0 0 0"/><axis xyz="0 0 0"/></joint>
  <link name="base_link"><collision><geometry><cylinder radius="0.06" length="0.1"/></geometry></collision></link>
  <joint name="j1" type="continuous"><parent link="base_link"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit effort="10" velocity="3"/></joint>
  <link name="l1"/>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
  <link name="l2"><collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.03" length="0.25"/></geometry></collision></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="10" velocity="3"/></joint>
  <link name="l3"><collision><origin xyz="0 0 0.12"/><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision></link>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0 0 0.25"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l4"/>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
  <link name="l5"/>
  <joint name="j6" type="continuous"><parent link="l5"/><child link="flange"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 0 1"/></joint>
  <link name="flange"/>
  <joint name="hand_joint" type="fixed"><parent link="flange"/><child link="hand"/>
    <origin xyz="0 0 0.01"/><axis xyz="0 0 0"/></joint>
  <link name="hand"><collision><origin xyz="0 0 0.02"/><geometry><box size="0.04 0.16 0.04"/></geometry></collision></link>
  <joint name="left_joint" type="prismatic"><parent link="hand"/><child link="left"/>
    <origin xyz="0 0 0.04"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="10" velocity="0.2"/></joint>
  <link name="left"><collision><origin xyz="0 0.005 0.03"/><geometry><box size="0.02 0.01 0.04"/></geometry></collision></link>
  <joint name="right_joint" type="prismatic"><parent link="hand"/><child link="right"/>
    <origin xyz="0 0 0.04"/><axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="10" velocity="0.2"/>
    <mimic joint="left_joint"/></joint>
  <link name="right"><collision><origin xyz="0 -0.005 0.03"/><geometry><box size="0.02 0.01 0.04"/></geometry></collision></link>
  <joint name="tcp_joint" type="fixed"><parent link="hand"/><child link="tcp"/>
    <origin xyz="0 0 0.07"/></joint>
  <link name="tcp"/>
</robot>
"#;

/// Its `robot.toml`: only the driven finger listed.
pub(crate) const ARM_TOML: &str = r#"
name = "arm6"
urdf = "arm6.urdf"
tcp_link = "tcp"
flange_link = "flange"
ready = [0.0, 0.3, 1.0, 0.0, 1.0, 0.0]
velocity_limits = [3.0, 3.0, 3.0, 3.0, 3.0, 3.0]
acceleration_limits = [10.0, 10.0, 10.0, 10.0, 10.0, 10.0]
[ik]
solver = "dls"
[gripper]
joints = ["left_joint"]
open_width = 0.08
speed = 0.1
hand_links = ["hand", "left", "right"]
[collision]
arm_margin = 0.01
hand_margin = 0.005
held_margin = 0.002
self_margin = 0.01
"#;

fn arm(toml: &str, urdf: &str) -> Result<Robot, RobotError> {
    Robot::from_texts(
        toml,
        Path::new("arm6/robot.toml"),
        urdf,
        Path::new("arm6/arm6.urdf"),
    )
}

/// The six-joint arm, loaded.
pub(crate) fn arm6() -> Robot {
    arm(ARM_TOML, ARM).unwrap()
}

#[test]
fn a_stock_like_arm_loads() {
    let robot = arm(ARM_TOML, ARM).unwrap();
    assert_eq!(robot.dof(), 6);
    assert_eq!(robot.links()[0].name, "world");
}

#[test]
fn continuous_joints_are_unbounded_and_answered_at_the_turn_nearest_the_seed() {
    let robot = arm(ARM_TOML, ARM).unwrap();
    assert_eq!(
        robot.continuous_joints(),
        [true, false, false, false, false, true]
    );
    assert_eq!(robot.joint_limits()[0], CONTINUOUS_RANGE);
    assert_eq!(robot.joint_limits()[5], CONTINUOUS_RANGE);
    // More than half a turn either way is a configuration, not clamped to ±π.
    let q = [4.0, 0.3, 1.0, 0.2, 1.0, -5.0];
    assert!(robot.check_joints(&q).is_ok());
    // A solution and the seed a whole turn apart on joint 6: the answer is the seed's turn.
    let target = robot.tcp_pose(&q);
    let seed = [4.0, 0.3, 1.0, 0.2, 1.0, -5.0 + std::f64::consts::TAU];
    let got = robot.ik(&target, &seed).unwrap();
    assert!((got[5] - seed[5]).abs() < 1e-3, "{got:?}");
    let moved = robot.nearest_turns(
        vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.1],
        &[6.0, 0.0, 0.0, 0.0, 0.0, -6.0],
    );
    // 0.1 + τ is nearest 6.0 but past the planned range: the turn within it.
    assert!((moved[0] - 0.1).abs() < 1e-12, "{moved:?}");
    assert!(
        (moved[5] - (0.1 - std::f64::consts::TAU)).abs() < 1e-12,
        "{moved:?}"
    );
}

/// A revolute joint bounded a turn either way (as UR's descriptions bound theirs) holds every
/// angle twice; a solver's restarts land on either turn, and the far one is the same pose a
/// whole turn of the joint away. Such a joint is answered at the turn nearest the seed, like a
/// continuous one; a joint whose range is less than a turn is never moved.
#[test]
fn revolute_joints_bounded_past_a_turn_are_answered_at_the_turn_nearest_the_seed() {
    use std::f64::consts::TAU;
    let urdf = ARM.replace(
        r#"<limit lower="-3" upper="3" effort="10" velocity="3"/>"#,
        &format!(
            r#"<limit lower="{}" upper="{TAU}" effort="10" velocity="3"/>"#,
            -TAU
        ),
    );
    let robot = arm(ARM_TOML, &urdf).unwrap();
    assert_eq!(robot.joint_limits()[3], [-TAU, TAU]);
    assert!(!robot.continuous_joints()[3]);
    let seed = [0.0, 0.3, 1.0, -2.9, 1.0, 0.0];
    // Joint 4 (±2π) a turn away from the seed comes back; joints 2 and 3 (ranges of 4 and
    // 5 rad) cannot turn within their limits and stay.
    let moved = robot.nearest_turns(vec![0.0, 1.9, -2.4, 3.0, 1.0, 0.0], &seed);
    assert!((moved[3] - (3.0 - TAU)).abs() < 1e-12, "{moved:?}");
    assert_eq!(moved[1..3], [1.9, -2.4]);
    // Every solution returned is at the seed's turn.
    let target = robot.tcp_pose(&[0.0, 0.3, 1.0, -2.9 + TAU, 1.0, 0.0]);
    let solutions = robot.ik_solutions(&target, &seed, 6);
    assert!(!solutions.is_empty());
    for q in &solutions {
        assert!(
            (q[3] - seed[3]).abs() <= std::f64::consts::PI + 1e-9,
            "{q:?}"
        );
    }
    // The stock arm (joint 4 within ±3 rad) is left as the solver answers.
    let stock = arm(ARM_TOML, ARM).unwrap();
    let kept = stock.nearest_turns(vec![0.0, 0.3, 1.0, 2.9, 1.0, 0.0], &seed);
    assert_eq!(kept[3], 2.9);
}

/// The links a revolute gripper joint swings (a linkage's knuckles and tips) are the ones
/// enclosed to the finer tolerance; the arm, the hand and prismatic fingers are not.
#[test]
fn only_the_links_a_revolute_gripper_swings_count_as_swung() {
    let robot = linkage_arm_with_bars();
    let swung: Vec<&str> = (0..robot.links().len())
        .filter(|&i| swung_by_gripper(robot.kinematics(), i))
        .map(|i| robot.links()[i].name.as_str())
        .collect();
    assert_eq!(swung, ["left_k", "left_tip", "right_k", "right_tip"]);
    let prismatic = arm(ARM_TOML, ARM).unwrap();
    assert!((0..prismatic.links().len()).all(|i| !swung_by_gripper(prismatic.kinematics(), i)));
    let panda = Robot::panda().unwrap();
    assert!((0..panda.links().len()).all(|i| !swung_by_gripper(panda.kinematics(), i)));
}

#[test]
fn a_mimicked_finger_moves_half_the_width_like_the_listed_one() {
    let robot = arm(ARM_TOML, ARM).unwrap();
    assert_eq!(robot.finger_joints(), ["left_joint", "right_joint"]);
    let left = robot.links().iter().position(|l| l.name == "left").unwrap();
    let right = robot
        .links()
        .iter()
        .position(|l| l.name == "right")
        .unwrap();
    for width in [0.0, 0.03, 0.08] {
        let poses = robot.link_poses(robot.ready(), width);
        let gap = (poses[left].translation.vector - poses[right].translation.vector).norm();
        assert!((gap - width).abs() < 1e-12, "{width}: {gap}");
    }
    assert!((robot.gripper_travel_time() - 0.4).abs() < 1e-12);
    assert!(HandModel::new(&robot).is_some());
}

#[test]
fn a_gripper_the_simulation_cannot_drive_is_refused_on_load() {
    let knuckle = ARM.replace(
        r#"<joint name="left_joint" type="prismatic">"#,
        r#"<joint name="left_joint" type="revolute">"#,
    );
    let e = arm(ARM_TOML, &knuckle).unwrap_err();
    assert!(
        matches!(&e, RobotError::Gripper { source: GripperError::NotParallel(j), .. } if j == "left"),
        "{e}"
    );
    let e = e.to_string();
    assert!(
        e.contains("arm6/robot.toml") && e.contains("parallel linkage"),
        "{e}"
    );
    let none = ARM_TOML.replace(r#"joints = ["left_joint"]"#, "joints = []");
    let e = arm(&none, ARM).unwrap_err();
    assert!(
        matches!(&e, RobotError::Gripper { source: GripperError::FingerCount(j), .. } if j.is_empty()),
        "{e}"
    );
    let padless = ARM.replace(
        r#"<link name="left"><collision><origin xyz="0 0.005 0.03"/><geometry><box size="0.02 0.01 0.04"/></geometry></collision></link>"#,
        r#"<link name="left"/>"#,
    );
    let e = arm(ARM_TOML, &padless).unwrap_err().to_string();
    assert!(e.contains("finger link `left`"), "{e}");
}

#[test]
fn every_contradiction_of_robot_toml_and_the_urdf_is_listed_at_once() {
    let toml = ARM_TOML
        .replace("ready = [0.0, 0.3,", "ready = [0.3,")
        .replace("velocity_limits = [3.0,", "velocity_limits = [10.0,")
        .replace(r#"hand_links = ["hand","#, r#"hand_links = ["palm","#);
    let e = arm(&toml, ARM).unwrap_err().to_string();
    assert!(e.starts_with("arm6/robot.toml: 3 problems:"), "{e}");
    assert!(
        e.contains("ready has 5 values but the arm has 6 joints"),
        "{e}"
    );
    assert!(
        e.contains("velocity_limits: 10 rad/s for `j1` exceeds its URDF limit of 3 rad/s"),
        "{e}"
    );
    assert!(
        e.contains("gripper.hand_links: `palm` is not a link of the URDF"),
        "{e}"
    );
}

#[test]
fn a_xacro_file_is_named_with_the_command_that_expands_it() {
    let e = Robot::from_texts(
        ARM_TOML,
        Path::new("arm6/robot.toml"),
        ARM,
        Path::new("arm6/arm6.urdf.xacro"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("arm6/arm6.urdf.xacro:") && e.contains("xacro robot.urdf.xacro > robot.urdf"),
        "{e}"
    );
}

/// No cap on links or collision elements: Franka's primitive model has 23 links and 44
/// elements; an arm of 60 links with two elements each loads and is checked whole.
#[test]
fn many_links_and_collision_elements_load() {
    let mut chain = String::new();
    let mut parent = "l1".to_string();
    for i in 0..54 {
        let link = format!("x{i}");
        chain.push_str(&format!(
            r#"<joint name="fx{i}" type="fixed"><parent link="{parent}"/><child link="{link}"/>
                <origin xyz="0 0 0.001"/></joint>
              <link name="{link}"><collision><geometry><sphere radius="0.01"/></geometry></collision>
                <collision><geometry><cylinder radius="0.005" length="0.01"/></geometry></collision></link>
            "#
        ));
        parent = link;
    }
    let urdf = ARM.replace("</robot>", &format!("{chain}</robot>"));
    let robot = arm(ARM_TOML, &urdf).unwrap();
    assert!(robot.links().len() > 60);
    let elements: usize = robot.links().iter().map(|l| l.shapes.len()).sum();
    assert!(elements > 110, "{elements}");
    let model = crate::collision::RobotCollision::new(&robot);
    assert!(model.self_pair_count() > 1000);
}

/// A parallel linkage on the six-joint arm: a knuckle turning each finger about y, the
/// fingertips counter-turned by mimic joints so that they stay parallel (as the 2F-85's).
fn linkage_arm() -> String {
    let start = ARM.find(r#"<joint name="left_joint""#).unwrap();
    let end = ARM.find(r#"<joint name="tcp_joint""#).unwrap();
    let knuckle = |side: &str, x: f64, sign: f64, mimic: &str| {
        format!(
            r#"<joint name="{side}_knuckle" type="revolute"><parent link="hand"/><child link="{side}_k"/>
                <origin xyz="{x} 0 0.04"/><axis xyz="0 1 0"/>
                <limit lower="0.1" upper="0.8" effort="1" velocity="1"/>{mimic}</joint>
              <link name="{side}_k"/>
              <joint name="{side}_tip_joint" type="revolute"><parent link="{side}_k"/><child link="{side}_tip"/>
                <origin xyz="0 0 0.04"/><axis xyz="0 1 0"/>
                <limit lower="-0.8" upper="0.8" effort="1" velocity="1"/>
                <mimic joint="left_knuckle" multiplier="{}"/></joint>
              <link name="{side}_tip"><collision><origin xyz="{} 0 0.02"/>
                <geometry><box size="0.01 0.02 0.04"/></geometry></collision></link>
            "#,
            -sign,
            -0.005 * x.signum()
        )
    };
    let fingers = knuckle("left", 0.005, 1.0, "")
        + &knuckle(
            "right",
            -0.005,
            -1.0,
            r#"<mimic joint="left_knuckle" multiplier="-1"/>"#,
        );
    format!("{}{fingers}{}", &ARM[..start], &ARM[end..])
}

/// The linkage arm's folder settings: the knuckle listed, the tips as hand links.
fn linkage_toml() -> String {
    ARM_TOML
        .replace(r#"joints = ["left_joint"]"#, r#"joints = ["left_knuckle"]"#)
        .replace(
            r#"hand_links = ["hand", "left", "right"]"#,
            r#"hand_links = ["hand", "left_tip", "right_tip"]"#,
        )
        .replace("open_width = 0.08", "open_width = 0.04")
}

/// The linkage arm with a bar on each knuckle, as the 2F-85's inner knuckles: links that
/// the closing swings in above the pads.
pub(crate) fn linkage_arm_with_bars() -> Robot {
    let bar = |side: &str| {
        format!(
            r#"<link name="{side}_k"><collision><origin xyz="0 0 0.02"/>
                <geometry><box size="0.006 0.01 0.03"/></geometry></collision></link>"#
        )
    };
    let urdf = linkage_arm()
        .replace(r#"<link name="left_k"/>"#, &bar("left"))
        .replace(r#"<link name="right_k"/>"#, &bar("right"));
    arm(&linkage_toml(), &urdf).unwrap()
}

/// The closing sweep leaves no opening unchecked: the knuckles are the linkage (not the
/// tips, which carry the pads), the openings checked run from fully open to the grasp, and at
/// any opening in between every corner of a knuckle's bar lies within half the sweep's step
/// of where it is at one of the two openings checked around it.
#[test]
fn the_closing_sweep_holds_the_linkage_at_every_opening() {
    use crate::hand::SWEEP_STEP;
    use rand::{Rng, SeedableRng};
    let robot = linkage_arm_with_bars();
    let hand = HandModel::build(&robot).unwrap();
    let names: Vec<&str> = hand
        .linkage
        .iter()
        .map(|&i| robot.links()[i].name.as_str())
        .collect();
    assert_eq!(names, ["left_k", "right_k"]);
    let q = robot.ready();
    let (open, grasp) = (robot.open_width(), 0.01);
    let (openings, step) = hand.closing_openings(&robot, q, open, grasp);
    assert!(step > 0.0 && step <= SWEEP_STEP, "{step}");
    assert_eq!((openings[0], openings[openings.len() - 1]), (open, grasp));
    assert!(openings.windows(2).all(|w| w[1] < w[0]));
    let corners: Vec<(usize, Point3<f64>)> = hand
        .linkage_shapes(&robot)
        .into_iter()
        .flat_map(|(link, geometry, origin)| {
            let Geometry::Box { size } = *geometry else {
                panic!("{geometry:?}")
            };
            (0..8).map(move |k| {
                let sign = |bit: usize| if k >> bit & 1 == 0 { -0.5 } else { 0.5 };
                let c = Point3::new(sign(0) * size[0], sign(1) * size[1], sign(2) * size[2]);
                (link, origin * c)
            })
        })
        .collect();
    let at = |w: f64| -> Vec<Point3<f64>> {
        let poses = robot.link_poses(q, w);
        corners.iter().map(|(link, c)| poses[*link] * c).collect()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
    let mut moved = 0.0f64;
    for _ in 0..300 {
        let w = rng.gen_range(grasp..open);
        let k = openings.iter().position(|&o| o <= w).unwrap();
        let (wider, narrower) = (at(openings[k - 1]), at(openings[k]));
        for ((p, a), b) in at(w).iter().zip(&wider).zip(&narrower) {
            let nearest = (p - a).norm().min((p - b).norm());
            assert!(nearest <= 0.5 * step * 1.001, "{w}: {nearest} > {step} / 2");
            moved = moved.max((p - at(open)[0]).norm());
        }
    }
    // The bars do swing: the check is not vacuous.
    assert!(moved > 0.01, "{moved}");
}

/// The clearance the planner reads is the least distance over the whole closing, less at
/// most half a step: never more than the distance at any opening (measured here at 2,000),
/// and never below it by more than half a step. An object between the pads reaching up into
/// the bars' sweep is found pressed; prismatic fingers have no linkage.
#[test]
fn the_closing_clearance_is_the_least_over_the_closing() {
    use crate::hand::closing_clearance;
    use crate::parry_convert::{distance, object_shape, robot_shape};
    use akl_scene::Shape;
    let robot = linkage_arm_with_bars();
    let hand = HandModel::build(&robot).unwrap();
    let q = robot.ready();
    let tcp = robot.tcp_pose(q);
    let grasp = 0.012;
    let clearance_to = |height: f64, below: f64| {
        let shape = Shape::Box {
            size: [0.01, grasp, height],
        };
        // The box between the pads, its top `below` the TCP along the approach.
        let pose = tcp * Pose::translation(0.0, 0.0, below + 0.5 * height);
        let c = closing_clearance(&robot, &hand, q, grasp, &shape, &pose).unwrap();
        let (object, fix) = object_shape(&shape, 0.0);
        let least = (0..=2000)
            .map(|k| {
                let w = robot.open_width() + (grasp - robot.open_width()) * f64::from(k) / 2000.0;
                let poses = robot.link_poses(q, w);
                hand.linkage_shapes(&robot)
                    .into_iter()
                    .map(|(link, geometry, origin)| {
                        let (s, f) = robot_shape(geometry, 0.0);
                        distance(&s, &(poses[link] * origin * f), &object, &(pose * fix)).unwrap()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(f64::INFINITY, f64::min);
        (c.clearance, least)
    };
    let (_, step) = hand.closing_openings(&robot, q, robot.open_width(), grasp);
    let mut found = Vec::new();
    for below in [-0.08, -0.04, -0.02, 0.0, 0.02] {
        let (c, least) = clearance_to(0.3, below);
        assert!(
            c <= least + 1e-6 && least - c <= 0.5 * step + 1e-4,
            "{below}: {c} {least}"
        );
        found.push(c);
    }
    // Reaching up into the hand, the object meets the bars; well below the pads, it does not.
    assert!(found[0] < 0.0 && found[4] > 0.0, "{found:?}");
    let panda = Robot::panda().unwrap();
    let shape = Shape::Sphere { radius: 0.01 };
    let panda_hand = HandModel::build(&panda).unwrap();
    assert!(panda_hand.linkage.is_empty());
    let pose = panda.tcp_pose(panda.ready());
    assert!(closing_clearance(&panda, &panda_hand, panda.ready(), 0.02, &shape, &pose).is_none());
}

#[test]
fn a_parallel_linkage_is_driven_by_the_gap_between_its_pads() {
    let robot = arm(&linkage_toml(), &linkage_arm()).unwrap();
    let hand = HandModel::build(&robot).unwrap();
    assert!(robot.kinematics().width_map().is_some());
    let face = |poses: &[Pose], k: usize| {
        let f = &hand.fingers[k];
        poses[f.link].transform_point(&Point3::from(f.face_centre()))
    };
    for width in [0.01, 0.025, 0.04] {
        let poses = robot.link_poses(robot.ready(), width);
        let gap = (face(&poses, 0) - face(&poses, 1)).norm();
        assert!((gap - width).abs() < 1e-3, "{width}: {gap}");
        // The tips keep the palm's orientation (the pads stay parallel).
        let palm = poses[hand.palm_link].rotation;
        for f in &hand.fingers {
            assert!(poses[f.link].rotation.angle_to(&palm) < 1e-9);
        }
    }
}

/// A `[mount]` stands the robot elsewhere in the task's robot base frame: every link pose and
/// the TCP move by the mount pose, inverse kinematics answers targets through it (the numerical
/// solvers and the analytic Panda solver alike), and a non-finite mount is refused.
#[test]
fn a_mount_stands_the_robot_at_its_pose() {
    use crate::config::MountConfig;
    let mount = MountConfig {
        xyz: [0.1, -0.05, 0.2],
        rpy: [0.0, 0.0, 0.5],
    };
    let table = "\n[mount]\nxyz = [0.1, -0.05, 0.2]\nrpy = [0.0, 0.0, 0.5]\n";
    let cases = [
        (
            arm(ARM_TOML, ARM).unwrap(),
            arm(&format!("{ARM_TOML}{table}"), ARM).unwrap(),
        ),
        (
            Robot::panda().unwrap(),
            Robot::panda_with(&format!("{}{table}", crate::robot::PANDA_TOML)).unwrap(),
        ),
    ];
    for (standing, mounted) in &cases {
        assert_eq!(mounted.config().mount, Some(mount));
        let q = standing.ready();
        let (a, b) = (standing.link_poses(q, 0.02), mounted.link_poses(q, 0.02));
        for (p, m) in a.iter().zip(&b) {
            let moved = mount.pose() * p;
            assert!((moved.translation.vector - m.translation.vector).norm() < 1e-12);
            assert!(moved.rotation.angle_to(&m.rotation) < 1e-12);
        }
        let target = mounted.tcp_pose(q);
        assert!(
            (mount.pose() * standing.tcp_pose(q))
                .translation
                .vector
                .metric_distance(&target.translation.vector)
                < 1e-12
        );
        let solved = mounted.ik(&target, q).unwrap();
        let reached = mounted.tcp_pose(&solved);
        assert!((reached.translation.vector - target.translation.vector).norm() < 1e-4);
    }
    let bad = format!("{ARM_TOML}\n[mount]\nxyz = [0.1, nan, 0.0]\n");
    let e = arm(&bad, ARM).unwrap_err().to_string();
    assert!(e.contains("mount holds a non-finite number"), "{e}");
}
