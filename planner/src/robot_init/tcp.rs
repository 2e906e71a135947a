//! The guesses that need the robot's kinematics: the TCP between the fingertip pads, the
//! gripper's opening, the links on the mount, and a ready pose.

use super::pairs::{link_shapes, meet};
use super::structure::{GripperKind, Structure};
use crate::hand::HandModel;
use crate::robot::Robot;
use akl_tsr::nalgebra::{Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use akl_tsr::rpy::rpy_from_rotation;
use akl_tsr::Pose;
use rand::{Rng, SeedableRng};
use serde::Serialize;

/// The TCP found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TcpGuess {
    /// The link written as `tcp_link`.
    pub link: String,
    /// Its position in the palm link's frame (metres).
    pub xyz: [f64; 3],
    /// Its orientation in the palm link's frame (roll, pitch, yaw).
    pub rpy: [f64; 3],
    /// The URDF joint and link added for it, when no link of the URDF lies there.
    pub added: Option<String>,
    /// What to review, if anything.
    pub note: Option<String>,
}

/// How far an existing link may lie from the guessed TCP and still be taken as it.
const SAME_POSITION: f64 = 0.005;
/// How far (radians) an existing link's axes may turn from the guessed TCP's.
const SAME_ANGLE: f64 = 0.09;

/// The middle of each joint's limits (a start before a ready pose is found).
pub(super) fn middle_of_limits(joints: &[&urdf_rs::Joint]) -> Vec<f64> {
    joints
        .iter()
        .map(|j| match j.joint_type {
            urdf_rs::JointType::Continuous => 0.0,
            _ => 0.5 * (j.limit.lower + j.limit.upper),
        })
        .collect()
}

/// The gripper's full opening (the sum of each finger's travel) and finger speed (half the
/// URDF's velocity limit, as the Panda's default is, at most 0.1 m/s).
pub(super) fn opening(urdf: &urdf_rs::Robot, s: &Structure) -> (f64, f64) {
    let joint = |n: &String| urdf.joints.iter().find(|j| j.name == *n);
    let travel: f64 = s
        .finger_joints
        .iter()
        .filter_map(joint)
        .map(|j| (j.limit.upper - j.limit.lower).abs())
        .sum();
    let speed = s
        .gripper_joints
        .first()
        .and_then(joint)
        .map_or(0.1, |j| (0.5 * j.limit.velocity).clamp(0.01, 0.1));
    match s.gripper {
        GripperKind::Parallel if travel > 0.0 => (travel, speed),
        // A linkage's opening is not a joint's travel: 85 mm is the 2F-85's stroke, for a
        // folder that is refused on load anyway.
        _ => (0.085, speed),
    }
}

/// The TCP of `robot` (loaded with its palm as TCP): between the fingertip pads closed, z
/// pointing from the fingers' mounts towards the pads, y along the closing axis. An existing
/// link fixed to the palm within 5 mm and 5° of it is taken; otherwise a link `akl_tcp` is
/// added.
pub(super) fn guess_tcp(robot: &Robot, s: &Structure) -> TcpGuess {
    let links = robot.links();
    let palm = robot.kinematics().link_index(&s.palm).unwrap_or(0);
    let poses = robot.link_poses(robot.ready(), robot.open_width());
    let in_palm = |i: usize| poses[palm].inverse() * poses[i];
    let (centre, approach, closing, note) = match (s.gripper, HandModel::build(robot)) {
        (GripperKind::Parallel | GripperKind::Linkage, Ok(hand)) => {
            // The pads closed, where they meet: a linkage's pads travel along the approach as
            // it closes (the 2F-85's by 13.4 mm, furthest from the palm closed), so at any
            // opening they close on something at or above this point, never deeper than the
            // spec puts the TCP; prismatic fingers' pads stay at one height.
            // The closing axis is taken open, where the pads are apart.
            let face = |poses: &[Pose]| {
                hand.fingers.map(|f| {
                    (poses[palm].inverse() * poses[f.link])
                        .transform_point(&Point3::from(f.face_centre()))
                        .coords
                })
            };
            let [a, b] = face(&poses);
            let [ca, cb] = face(&robot.link_poses(robot.ready(), 0.0));
            // Prismatic fingers hang from the palm: their joints are the mounts. A linkage's
            // tips hang from knuckles: the approach is from the palm's origin.
            let mount = match s.gripper {
                GripperKind::Parallel => {
                    0.5 * (links[hand.fingers[0].link].origin.translation.vector
                        + links[hand.fingers[1].link].origin.translation.vector)
                }
                _ => Vector3::zeros(),
            };
            let centre = 0.5 * (ca + cb);
            (centre, centre - mount, a - b, None)
        }
        (GripperKind::Linkage | GripperKind::Parallel, _) => {
            // The two leaves of the gripper farthest from the palm: the fingertips.
            let mut tips: Vec<(f64, Vector3<f64>)> = (0..links.len())
                .filter(|&i| {
                    !links.iter().any(|l| l.parent == Some(i)) && descends(robot, i, palm)
                })
                .map(|i| {
                    let p = in_palm(i).translation.vector;
                    (p.norm(), p)
                })
                .collect();
            tips.sort_by(|x, y| y.0.total_cmp(&x.0));
            match tips[..] {
                [(_, a), (_, b), ..] => {
                    let centre = 0.5 * (a + b);
                    let note = "tcp: placed between the fingertip links' origins (the pads of this gripper are not modelled): check it lies between the pads".to_string();
                    (centre, centre, b - a, Some(note))
                }
                _ => (Vector3::zeros(), Vector3::z(), Vector3::y(), None),
            }
        }
        (GripperKind::None, _) => (
            Vector3::zeros(),
            Vector3::z(),
            Vector3::y(),
            Some("tcp: no gripper, so the TCP is the arm's last link; move it to the tool's working point".into()),
        ),
    };
    let z = approach.try_normalize(1e-9).unwrap_or_else(Vector3::z);
    let y = (closing - closing.dot(&z) * z)
        .try_normalize(1e-9)
        .unwrap_or_else(|| z.cross(&Vector3::x()).normalize());
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
        Matrix3::from_columns(&[y.cross(&z), y, z]),
    ));
    let pose = Pose::from_parts(Translation3::from(centre), rotation);
    // Micrometres and microradians: the pads are given in single precision.
    let round = |v: f64| (v * 1e6).round() / 1e6 + 0.0;
    let rpy = rpy_from_rotation(&rotation).map(round);
    let xyz = [centre.x, centre.y, centre.z].map(round);
    // An existing link fixed to the palm at that pose (or the palm itself with no gripper).
    let same = |i: usize| {
        let p = in_palm(i);
        let axis = |k: usize| p.rotation * Vector3::ith(k, 1.0);
        (p.translation.vector - pose.translation.vector).norm() <= SAME_POSITION
            && axis(2).angle(&z) <= SAME_ANGLE
            && axis(1).dot(&y).abs() >= SAME_ANGLE.cos()
    };
    let existing = if s.gripper == GripperKind::None {
        Some(palm)
    } else {
        (0..links.len()).find(|&i| fixed_below(robot, i, palm) && same(i))
    };
    if let Some(i) = existing {
        return TcpGuess {
            link: links[i].name.clone(),
            xyz,
            rpy,
            added: None,
            note,
        };
    }
    let mut name = "akl_tcp".to_string();
    while robot.kinematics().link_index(&name).is_some() {
        name.push('_');
    }
    let added = format!(
        "  <!-- The tool centre point, added by `akl robot init`. -->\n  <joint name=\"{name}_joint\" type=\"fixed\">\n    <parent link=\"{}\"/>\n    <child link=\"{name}\"/>\n    <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\n  </joint>\n  <link name=\"{name}\"/>\n",
        s.palm, xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
    );
    TcpGuess {
        link: name,
        xyz,
        rpy,
        added: Some(added),
        note,
    }
}

/// Whether link `i` is `ancestor` or hangs below it.
fn descends(robot: &Robot, mut i: usize, ancestor: usize) -> bool {
    loop {
        if i == ancestor {
            return true;
        }
        match robot.links()[i].parent {
            Some(p) => i = p,
            None => return false,
        }
    }
}

/// Whether link `i` is `palm` or hangs below it by fixed joints only.
fn fixed_below(robot: &Robot, mut i: usize, palm: usize) -> bool {
    loop {
        if i == palm {
            return true;
        }
        let link = &robot.links()[i];
        match (link.parent, link.motion) {
            (Some(p), crate::fk::Motion::Fixed) => i = p,
            _ => return false,
        }
    }
}

/// The URDF text with `snippet` added before its closing `</robot>`.
pub(super) fn add_to_urdf(text: &str, snippet: &str) -> String {
    match text.rfind("</robot>") {
        Some(at) => format!("{}{snippet}{}", &text[..at], &text[at..]),
        None => format!("{text}{snippet}"),
    }
}

/// The links that stand on the mount: those no arm joint moves, and the link the first arm
/// joint turns when it turns about the vertical.
pub(super) fn mount_links(robot: &Robot) -> Vec<usize> {
    let links = robot.links();
    let arm = robot.kinematics().arm_links();
    let poses = robot.link_poses(robot.ready(), 0.0);
    let turns_on_the_mount = |f: usize| match links[f].motion {
        crate::fk::Motion::Revolute { axis, .. } => {
            let parent = links[f].parent.map_or(Pose::identity(), |p| poses[p]);
            let vertical = parent.rotation * links[f].origin.rotation * axis.into_inner();
            vertical.z.abs() > 0.99
        }
        _ => false,
    };
    (0..links.len())
        .filter(|&i| {
            let moved = arm.iter().any(|&k| descends(robot, i, k));
            !moved || (arm.first() == Some(&i) && turns_on_the_mount(i))
        })
        .collect()
}

/// A ready pose: the TCP pointing straight down in front of the base, at 35 % of the arm's
/// reach forward and 40 % up; of the collision-free solutions from several seeds, the one
/// farthest (relative to each joint's range) from the joint limits.
pub(super) fn ready_pose(robot: &Robot, checked: &[(usize, usize)]) -> Option<Vec<f64>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let limits = robot.joint_limits();
    let random = |rng: &mut rand_chacha::ChaCha8Rng| -> Vec<f64> {
        limits
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..=*hi))
            .collect()
    };
    let reach = (0..2000)
        .map(|_| robot.tcp_pose(&random(&mut rng)).translation.vector.norm())
        .fold(0.0, f64::max);
    let down = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let shapes = link_shapes(robot);
    let free = |q: &[f64]| {
        let poses = robot.link_poses(q, robot.open_width());
        checked.iter().all(|&(a, b)| !meet(&shapes, &poses, a, b))
    };
    let margin = |q: &[f64]| {
        q.iter()
            .zip(limits)
            .zip(robot.continuous_joints())
            .filter(|(_, c)| !**c)
            .map(|((v, [lo, hi]), _)| (v - lo).min(hi - v) / (hi - lo).max(1e-9))
            .fold(f64::INFINITY, f64::min)
    };
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (forward, up) in [(0.35, 0.4), (0.3, 0.3), (0.45, 0.3), (0.3, 0.5)] {
        let target = Pose::from_parts(Translation3::new(forward * reach, 0.0, up * reach), down);
        let middle: Vec<f64> = limits.iter().map(|[lo, hi]| 0.5 * (lo + hi)).collect();
        let seeds = std::iter::once(middle).chain((0..40).map(|_| random(&mut rng)));
        for seed in seeds.collect::<Vec<_>>() {
            let Ok(q) = robot.ik(&target, &seed) else {
                continue;
            };
            if robot.check_joints(&q).is_ok() && free(&q) {
                let m = margin(&q);
                if best.as_ref().is_none_or(|(b, _)| m > *b) {
                    best = Some((m, q));
                }
            }
        }
        if best.is_some() {
            break;
        }
    }
    best.map(|(_, q)| q)
}
