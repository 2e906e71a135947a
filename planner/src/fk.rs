//! Forward kinematics compiled from the k tree into flat arrays, so that a configuration's
//! link poses cost a few hundred nanoseconds and no allocation (the planner evaluates them
//! millions of times). Tests check it against k's own forward kinematics.

use crate::error::UrdfError;
use crate::geometry::{Geometry, LinkShape, ShapeRole};
use akl_tsr::nalgebra::{Matrix6xX, Translation3, Unit, UnitQuaternion, Vector3};
use akl_tsr::Pose;
use std::collections::BTreeMap;

/// What drives a joint's position: `scale · input + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drive {
    /// Held at a constant position (joints neither on the arm nor in the gripper).
    Constant(f64),
    /// Arm joint `index` (scaled and offset when it is mimicked).
    Arm {
        /// Index in the arm configuration.
        index: usize,
        /// Multiplier.
        scale: f64,
        /// Offset added after scaling.
        offset: f64,
    },
    /// The gripper opening width (scaled and offset).
    Width {
        /// Multiplier.
        scale: f64,
        /// Offset added after scaling.
        offset: f64,
    },
}

/// How a link moves relative to its parent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Rigidly attached.
    Fixed,
    /// Turns about `axis` (in the joint frame) by the driven angle.
    Revolute {
        /// Unit axis.
        axis: Unit<Vector3<f64>>,
        /// The position's source.
        drive: Drive,
    },
    /// Slides along `axis` by the driven distance.
    Prismatic {
        /// Unit axis.
        axis: Unit<Vector3<f64>>,
        /// The position's source.
        drive: Drive,
    },
}

/// A link with the joint that attaches it to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Link name.
    pub name: String,
    /// Name of the joint attaching it to its parent (`root` for the base link).
    pub joint: String,
    /// Index of the parent link; `None` for the base link.
    pub parent: Option<usize>,
    /// Joint frame in the parent link frame (the URDF joint origin).
    pub origin: Pose,
    /// How the joint moves.
    pub motion: Motion,
    /// Collision elements in the link frame.
    pub shapes: Vec<LinkShape>,
}

/// The robot's links in topological order (parents first) with compiled joint drives.
#[derive(Debug, Clone)]
pub struct Kinematics {
    links: Vec<Link>,
    dof: usize,
    tcp: usize,
    tcp_path: Vec<usize>,
    arm_links: Vec<usize>,
    /// For a linkage gripper (a revolute knuckle driving mimic joints): the knuckle angle for
    /// each pad gap, `[width, angle]` by increasing width. Without it the gripper input is
    /// the opening itself (prismatic fingers), or the knuckle angle while the map is made.
    width_map: Option<Vec<[f64; 2]>>,
}

/// Joint names and limits of the arm, as the compiler found them, and the gripper's joints.
#[derive(Debug, Clone)]
pub struct ArmJoints {
    /// Names, base to tip.
    pub names: Vec<String>,
    /// `[lower, upper]` limits; a continuous joint's are `[-2π, 2π]` (`CONTINUOUS_RANGE`).
    pub limits: Vec<[f64; 2]>,
    /// Whether each is revolute (else prismatic).
    pub revolute: Vec<bool>,
    /// Whether each is continuous (a URDF `continuous` joint: it turns without end).
    pub continuous: Vec<bool>,
    /// Every joint the opening width moves: the gripper joints `robot.toml` lists, then the
    /// joints that mimic one of them and are not listed.
    pub fingers: Vec<String>,
}

/// Mimic relations read from the URDF: joint → (followed joint, multiplier, offset).
pub(crate) type Mimics = BTreeMap<String, (String, f64, f64)>;

/// The range planned over for a continuous joint: a turn either way of zero (as UR's own
/// descriptions bound their joints), so that every angle lies in it twice and from anywhere
/// in it every angle is within half a turn. The joint itself has no limit: inverse
/// kinematics answers the turn nearest its seed, and `akl robot info` marks the joint
/// continuous.
pub(crate) const CONTINUOUS_RANGE: [f64; 2] = [-std::f64::consts::TAU, std::f64::consts::TAU];

/// How far a joint may move, as its URDF says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum JointRange {
    /// A revolute or prismatic joint's `<limit lower upper>`.
    Bounded([f64; 2]),
    /// A continuous joint: no limit.
    Continuous,
}

/// What the URDF says about its joints that k's tree drops: mimic relations and ranges
/// (k reads a revolute joint whose limits are equal as unlimited, and a continuous joint
/// with a `<limit>` as limited).
#[derive(Debug, Clone, Default)]
pub struct UrdfJoints {
    /// Mimic relations.
    pub(crate) mimics: Mimics,
    /// The range of every movable joint, by name.
    pub(crate) ranges: BTreeMap<String, JointRange>,
}

impl UrdfJoints {
    /// Reads the mimic relations and ranges of a URDF's joints.
    pub fn of(urdf: &urdf_rs::Robot) -> UrdfJoints {
        let mut out = UrdfJoints::default();
        for j in &urdf.joints {
            if let Some(m) = &j.mimic {
                out.mimics.insert(
                    j.name.clone(),
                    (
                        m.joint.clone(),
                        m.multiplier.unwrap_or(1.0),
                        m.offset.unwrap_or(0.0),
                    ),
                );
            }
            let range = match j.joint_type {
                urdf_rs::JointType::Continuous => JointRange::Continuous,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Prismatic => {
                    JointRange::Bounded([j.limit.lower, j.limit.upper])
                }
                _ => continue,
            };
            out.ranges.insert(j.name.clone(), range);
        }
        out
    }

    /// The range a joint is planned over (see [`CONTINUOUS_RANGE`]); `None` for a fixed or
    /// unknown joint.
    fn planned_range(&self, name: &str) -> Option<[f64; 2]> {
        self.ranges.get(name).map(|r| match r {
            JointRange::Bounded(limits) => *limits,
            JointRange::Continuous => CONTINUOUS_RANGE,
        })
    }
}

impl Kinematics {
    /// Compiles the k tree. The arm joints are the movable joints from the base to `tcp_link`
    /// that are not gripper joints; gripper joints and the joints mimicking them follow the
    /// opening width (each of the n moves `width / n`, times its mimic multiplier); other
    /// mimic joints follow their source; other joints stay at the position nearest zero
    /// within their limits.
    pub fn compile(
        chain: &k::Chain<f64>,
        tcp_link: &str,
        gripper_joints: &[String],
        joints: &UrdfJoints,
    ) -> Result<(Kinematics, ArmJoints), UrdfError> {
        let mimics = &joints.mimics;
        let nodes: Vec<&k::Node<f64>> = chain.iter().collect();
        let mut parents = Vec::with_capacity(nodes.len());
        for node in &nodes {
            let parent =
                match node.parent() {
                    Some(p) => Some(nodes.iter().position(|n| **n == p).ok_or_else(|| {
                        UrdfError::Joint {
                            joint: node.joint().name.clone(),
                            problem: "its parent is not in the tree".into(),
                        }
                    })?),
                    None => None,
                };
            parents.push(parent);
        }
        let link_name = |n: &k::Node<f64>| n.link().as_ref().map(|l| l.name.clone());
        let tcp = nodes
            .iter()
            .position(|n| link_name(n).as_deref() == Some(tcp_link))
            .ok_or_else(|| UrdfError::NotInUrdf {
                field: "tcp_link",
                name: tcp_link.to_string(),
                kind: "link",
            })?;
        let mut tcp_path = vec![tcp];
        while let Some(p) = parents[*tcp_path.last().unwrap_or(&0)] {
            tcp_path.push(p);
        }
        tcp_path.reverse();
        for g in gripper_joints {
            if !nodes.iter().any(|n| n.joint().name == *g) {
                return Err(UrdfError::NotInUrdf {
                    field: "gripper joint",
                    name: g.clone(),
                    kind: "joint",
                });
            }
        }
        let mut fingers = gripper_joints.to_vec();
        for node in &nodes {
            let name = &node.joint().name;
            let follows = mimics.get(name).map(|(source, ..)| source);
            if follows.is_some_and(|s| gripper_joints.contains(s)) && !fingers.contains(name) {
                fingers.push(name.clone());
            }
        }
        let mut arm = ArmJoints {
            names: Vec::new(),
            limits: Vec::new(),
            revolute: Vec::new(),
            continuous: Vec::new(),
            fingers,
        };
        for &i in &tcp_path {
            let joint = nodes[i].joint();
            let movable = !matches!(joint.joint_type, k::JointType::Fixed);
            if movable && !gripper_joints.contains(&joint.name) && !mimics.contains_key(&joint.name)
            {
                let range = joints
                    .planned_range(&joint.name)
                    .unwrap_or(CONTINUOUS_RANGE);
                arm.names.push(joint.name.clone());
                arm.limits.push(range);
                arm.revolute
                    .push(matches!(joint.joint_type, k::JointType::Rotational { .. }));
                arm.continuous.push(matches!(
                    joints.ranges.get(&joint.name),
                    Some(JointRange::Continuous)
                ));
            }
        }
        if arm.names.is_empty() {
            return Err(UrdfError::NoArmJoint(tcp_link.to_string()));
        }
        // Prismatic fingers share the opening; a linkage's knuckle takes the input whole
        // (its angle, mapped from the opening once the pads are known).
        let knuckle = gripper_joints.iter().any(|g| {
            nodes.iter().any(|n| {
                n.joint().name == *g
                    && matches!(n.joint().joint_type, k::JointType::Rotational { .. })
            })
        });
        let finger_scale = if knuckle {
            1.0
        } else {
            1.0 / arm.fingers.len().max(1) as f64
        };
        let base_drive = |name: &str, limits: Option<[f64; 2]>| -> Drive {
            if let Some(index) = arm.names.iter().position(|n| n == name) {
                Drive::Arm {
                    index,
                    scale: 1.0,
                    offset: 0.0,
                }
            } else if gripper_joints.iter().any(|g| g == name) {
                Drive::Width {
                    scale: finger_scale,
                    offset: 0.0,
                }
            } else {
                Drive::Constant(limits.map_or(0.0, |[lo, hi]| 0.0f64.clamp(lo, hi)))
            }
        };
        let limits_of = |name: &str| joints.planned_range(name);
        let mut links = Vec::with_capacity(nodes.len());
        for (i, node) in nodes.iter().enumerate() {
            let (joint_name, joint_type, origin) = {
                let joint = node.joint();
                (joint.name.clone(), joint.joint_type, *joint.origin())
            };
            let drive = match mimics.get(&joint_name) {
                Some((source, scale, offset)) => match base_drive(source, limits_of(source)) {
                    Drive::Arm { index, .. } => Drive::Arm {
                        index,
                        scale: *scale,
                        offset: *offset,
                    },
                    Drive::Width { scale: s, .. } => Drive::Width {
                        scale: s * scale,
                        offset: *offset,
                    },
                    Drive::Constant(c) => Drive::Constant(scale * c + offset),
                },
                None => base_drive(&joint_name, limits_of(&joint_name)),
            };
            let motion = match joint_type {
                k::JointType::Fixed => Motion::Fixed,
                k::JointType::Rotational { axis } => Motion::Revolute { axis, drive },
                k::JointType::Linear { axis } => Motion::Prismatic { axis, drive },
            };
            let (name, shapes) = match node.link().as_ref() {
                Some(link) => {
                    let mut shapes = Vec::new();
                    for c in &link.collisions {
                        let geometry =
                            Geometry::from_k(&c.geometry).ok_or_else(|| UrdfError::Geometry {
                                link: link.name.clone(),
                                geometry: format!("{:?}", c.geometry),
                            })?;
                        if let Some(geometry) = geometry {
                            shapes.push(LinkShape {
                                geometry,
                                origin: *c.origin(),
                                role: ShapeRole::Exact,
                            });
                        }
                    }
                    (link.name.clone(), shapes)
                }
                None => (format!("{joint_name}_link"), Vec::new()),
            };
            links.push(Link {
                name,
                joint: joint_name,
                parent: parents[i],
                origin,
                motion,
                shapes,
            });
        }
        let arm_links = arm
            .names
            .iter()
            .filter_map(|n| links.iter().position(|l| l.joint == *n))
            .collect();
        let dof = arm.names.len();
        Ok((
            Kinematics {
                links,
                dof,
                tcp,
                tcp_path,
                arm_links,
                width_map: None,
            },
            arm,
        ))
    }

    /// The links, parents before children.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Number of arm joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Index of the TCP link.
    pub(crate) fn tcp_index(&self) -> usize {
        self.tcp
    }

    /// Index of the link named `name`.
    pub(crate) fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Adds collision shapes to link `link` (the grown hull enclosing its meshes).
    pub(crate) fn add_shapes(&mut self, link: usize, shapes: impl IntoIterator<Item = LinkShape>) {
        self.links[link].shapes.extend(shapes);
    }

    /// Indices of the links moved by each arm joint (the joint's child link), in arm order.
    pub(crate) fn arm_links(&self) -> &[usize] {
        &self.arm_links
    }

    /// Stands the robot at `mount`: the root link's pose in the base frame (every link pose
    /// and the TCP are then given in the frame the robot stands in).
    pub(crate) fn set_mount(&mut self, mount: Pose) {
        if let Some(root) = self.links.first_mut() {
            root.origin = mount * root.origin;
        }
    }

    /// Sets the linkage's map from pad gap to knuckle angle (`[width, angle]` pairs by
    /// increasing width, at least two).
    pub(crate) fn set_width_map(&mut self, map: Vec<[f64; 2]>) {
        self.width_map = Some(map);
    }

    /// The linkage's map from pad gap to knuckle angle, if the gripper is a linkage.
    #[cfg(test)]
    pub(crate) fn width_map(&self) -> Option<&[[f64; 2]]> {
        self.width_map.as_deref()
    }

    /// The gripper input for opening `width`: the width itself, or the linkage's knuckle
    /// angle interpolated from its map (clamped to the map's ends).
    fn gripper_input(&self, width: f64) -> f64 {
        let Some(map) = self.width_map.as_deref() else {
            return width;
        };
        let at = map.partition_point(|[w, _]| *w < width);
        match (at.checked_sub(1).and_then(|i| map.get(i)), map.get(at)) {
            (Some([w0, a0]), Some([w1, a1])) if w1 > w0 => {
                a0 + (a1 - a0) * (width - w0) / (w1 - w0)
            }
            (_, Some([_, a])) | (Some([_, a]), None) => *a,
            (None, None) => width,
        }
    }

    fn position(&self, drive: Drive, q: &[f64], width: f64) -> f64 {
        match drive {
            Drive::Constant(c) => c,
            Drive::Arm {
                index,
                scale,
                offset,
            } => scale * q[index] + offset,
            Drive::Width { scale, offset } => scale * self.gripper_input(width) + offset,
        }
    }

    /// The joint's transform: origin then the motion at its driven position.
    fn local(&self, link: &Link, q: &[f64], width: f64) -> Pose {
        match link.motion {
            Motion::Fixed => link.origin,
            Motion::Revolute { axis, drive } => {
                let angle = self.position(drive, q, width);
                link.origin * UnitQuaternion::from_axis_angle(&axis, angle)
            }
            Motion::Prismatic { axis, drive } => {
                let d = self.position(drive, q, width);
                link.origin * Translation3::from(axis.into_inner() * d)
            }
        }
    }

    /// Writes the pose of every link in the base frame into `out` (one per link, in
    /// [`Kinematics::links`] order). `q` has [`Kinematics::dof`] values; `width` is the gripper
    /// opening. Panics if `out` or `q` is too short (a programming error, never input).
    pub fn link_poses_into(&self, q: &[f64], width: f64, out: &mut [Pose]) {
        self.link_poses_at(&Pose::identity(), q, width, out);
    }

    /// [`Kinematics::link_poses_into`] with the base placed at `base` (e.g. where the robot
    /// stands in the world): one product per link fewer than placing each pose afterwards.
    pub fn link_poses_at(&self, base: &Pose, q: &[f64], width: f64, out: &mut [Pose]) {
        for (i, link) in self.links.iter().enumerate() {
            let local = self.local(link, q, width);
            out[i] = match link.parent {
                Some(p) => out[p] * local,
                None => base * local,
            };
        }
    }

    /// The pose of every link in the base frame (see [`Kinematics::link_poses_into`]).
    pub fn link_poses(&self, q: &[f64], width: f64) -> Vec<Pose> {
        let mut out = vec![Pose::identity(); self.links.len()];
        self.link_poses_into(q, width, &mut out);
        out
    }

    /// The TCP pose in the base frame; only the links between base and TCP are evaluated.
    pub fn tcp_pose(&self, q: &[f64]) -> Pose {
        let mut pose = Pose::identity();
        for &i in &self.tcp_path {
            pose *= self.local(&self.links[i], q, 0.0);
        }
        pose
    }

    /// The TCP pose and its geometric Jacobian (rows: linear then angular velocity in the base
    /// frame; one column per arm joint).
    pub(crate) fn tcp_jacobian(&self, q: &[f64]) -> (Pose, Matrix6xX<f64>) {
        let mut frames = Vec::with_capacity(self.tcp_path.len());
        let mut pose = Pose::identity();
        for &i in &self.tcp_path {
            let link = &self.links[i];
            let joint_frame = pose * link.origin;
            pose *= self.local(link, q, 0.0);
            frames.push((joint_frame, link.motion));
        }
        let tip = pose.translation.vector;
        let mut jac = Matrix6xX::zeros(self.dof);
        for (frame, motion) in frames {
            match motion {
                Motion::Revolute {
                    axis,
                    drive: Drive::Arm { index, scale, .. },
                } => {
                    let a = frame.rotation * axis.into_inner() * scale;
                    let v = a.cross(&(tip - frame.translation.vector));
                    for r in 0..3 {
                        jac[(r, index)] += v[r];
                        jac[(r + 3, index)] += a[r];
                    }
                }
                Motion::Prismatic {
                    axis,
                    drive: Drive::Arm { index, scale, .. },
                } => {
                    let a = frame.rotation * axis.into_inner() * scale;
                    for r in 0..3 {
                        jac[(r, index)] += a[r];
                    }
                }
                _ => {}
            }
        }
        (pose, jac)
    }
}

#[cfg(test)]
mod tests {
    use crate::robot::Robot;
    use akl_tsr::nalgebra::Vector3;
    use akl_tsr::Pose;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

    const REFERENCE_Q: [f64; 7] = [
        0.0,
        -FRAC_PI_4,
        0.0,
        -3.0 * FRAC_PI_4,
        0.0,
        FRAC_PI_2,
        FRAC_PI_4,
    ];

    /// Link poses from k's own forward kinematics, by link name.
    fn k_link_pose(robot: &Robot, q: &[f64], width: f64, link: &str) -> Pose {
        let chain = robot.chain();
        let positions: Vec<f64> = chain
            .iter_joints()
            .filter(|j| j.is_movable())
            .map(
                |j| match robot.joint_names().iter().position(|n| *n == j.name) {
                    Some(i) => q[i],
                    None => width / 2.0,
                },
            )
            .collect();
        chain.set_joint_positions(&positions).unwrap();
        chain.update_transforms();
        chain.find_link(link).unwrap().world_transform().unwrap()
    }

    #[test]
    fn k_reproduces_the_published_reference_pose() {
        let robot = Robot::panda().unwrap();
        let flange = k_link_pose(&robot, &REFERENCE_Q, 0.08, "fer_link8");
        let expected = Vector3::new(0.30689, 0.0, 0.59028);
        assert!(
            (flange.translation.vector - expected).norm() < 1e-5,
            "{flange}"
        );
        let further = flange * akl_tsr::nalgebra::Point3::new(0.0, 0.0, 0.105);
        assert!((further.coords - Vector3::new(0.30689, 0.0, 0.48528)).norm() < 1e-5);
    }

    #[test]
    fn the_tcp_at_the_reference_pose_points_down_between_the_fingers() {
        let robot = Robot::panda().unwrap();
        let tcp = robot.tcp_pose(&REFERENCE_Q);
        let expected = Vector3::new(0.30689, 0.0, 0.59028 - 0.1034);
        assert!((tcp.translation.vector - expected).norm() < 1e-5, "{tcp}");
        let z = tcp.rotation * Vector3::z();
        assert!((z + Vector3::z()).norm() < 1e-9, "tool z {z}");
        let flange = robot.flange_pose(&REFERENCE_Q);
        assert!((flange.translation.vector - Vector3::new(0.30689, 0.0, 0.59028)).norm() < 1e-5);
    }

    fn arb_q() -> impl Strategy<Value = Vec<f64>> {
        let robot = Robot::panda().unwrap();
        robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| *lo..*hi)
            .collect::<Vec<_>>()
    }

    proptest! {
        #[test]
        fn compiled_kinematics_match_k_for_every_link(q in arb_q(), width in 0.0..0.08f64) {
            let robot = Robot::panda().unwrap();
            let poses = robot.link_poses(&q, width);
            for (link, pose) in robot.links().iter().zip(&poses) {
                let reference = k_link_pose(&robot, &q, width, &link.name);
                prop_assert!((pose.translation.vector - reference.translation.vector).norm() < 1e-12, "{}", link.name);
                prop_assert!(pose.rotation.angle_to(&reference.rotation) < 1e-9, "{}", link.name);
            }
            let tcp = robot.tcp_pose(&q);
            prop_assert!((tcp.translation.vector - poses[robot.tcp_link()].translation.vector).norm() < 1e-12);
        }

        #[test]
        fn the_jacobian_matches_finite_differences(q in arb_q()) {
            let robot = Robot::panda().unwrap();
            let (pose, jac) = robot.kinematics().tcp_jacobian(&q);
            let h = 1e-7;
            for j in 0..7 {
                let mut qh = q.clone();
                qh[j] += h;
                let moved = robot.tcp_pose(&qh);
                let v = (moved.translation.vector - pose.translation.vector) / h;
                let w = (moved.rotation * pose.rotation.inverse()).scaled_axis() / h;
                for r in 0..3 {
                    prop_assert!((v[r] - jac[(r, j)]).abs() < 1e-5);
                    prop_assert!((w[r] - jac[(r + 3, j)]).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn fingers_open_symmetrically_about_the_tcp() {
        let robot = Robot::panda().unwrap();
        let poses = robot.link_poses(&REFERENCE_Q, 0.06);
        let index = |n: &str| robot.links().iter().position(|l| l.name == n).unwrap();
        let hand = poses[index("fer_hand")];
        let left = hand.inverse() * poses[index("fer_leftfinger")];
        let right = hand.inverse() * poses[index("fer_rightfinger")];
        assert!((left.translation.y - 0.03).abs() < 1e-12);
        assert!((right.translation.y + 0.03).abs() < 1e-12);
    }
}
