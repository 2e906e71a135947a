//! What a URDF's joint tree says about the robot: which joints make the gripper, which link
//! the fingers hang from, the arm's joints from the root to it, and the flange.

use crate::fk::UrdfJoints;
use serde::Serialize;
use std::collections::BTreeMap;
use urdf_rs::JointType;

/// The kind of gripper found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GripperKind {
    /// Two prismatic fingers on one link (the simulation drives these).
    Parallel,
    /// One actuated revolute knuckle with three or more `<mimic>` joints following it, as
    /// the Robotiq 2F-85 (the simulation cannot drive these yet).
    Linkage,
    /// No gripper found.
    None,
}

/// The structure of a robot's tree.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Structure {
    /// The root link.
    pub root: String,
    /// The arm's joints, base to tip.
    pub arm_joints: Vec<String>,
    /// The link the gripper hangs from (the last link of the arm when there is no gripper).
    pub palm: String,
    /// The mounting flange.
    pub flange: String,
    /// The gripper found.
    pub gripper: GripperKind,
    /// The gripper joints to list in `robot.toml` (not those that mimic them).
    pub gripper_joints: Vec<String>,
    /// Every joint the gripper's opening moves (listed and mimicking).
    pub finger_joints: Vec<String>,
}

/// Reads the structure of a validated URDF, or says why no arm can be found in it.
pub(super) fn structure(urdf: &urdf_rs::Robot) -> Result<Structure, String> {
    let joints = UrdfJoints::of(urdf);
    let by_child: BTreeMap<&str, &urdf_rs::Joint> = urdf
        .joints
        .iter()
        .map(|j| (j.child.link.as_str(), j))
        .collect();
    let root = urdf
        .links
        .iter()
        .find(|l| !by_child.contains_key(l.name.as_str()))
        .map(|l| l.name.clone())
        .ok_or("the URDF has no root link")?;
    let followers = |name: &str| -> Vec<&urdf_rs::Joint> {
        urdf.joints
            .iter()
            .filter(|j| joints.mimics.get(&j.name).is_some_and(|(s, ..)| s == name))
            .collect()
    };
    let movable = |j: &urdf_rs::Joint| !matches!(j.joint_type, JointType::Fixed);
    let driven = |j: &&urdf_rs::Joint| movable(j) && !joints.mimics.contains_key(&j.name);
    // Two prismatic fingers on one link: the driven prismatic joints whose subtree does not
    // move, with the prismatic joints that mimic them.
    let leaf = |j: &urdf_rs::Joint| {
        let mut stack = vec![j.child.link.as_str()];
        while let Some(link) = stack.pop() {
            for c in urdf.joints.iter().filter(|c| c.parent.link == link) {
                if movable(c) {
                    return false;
                }
                stack.push(&c.child.link);
            }
        }
        true
    };
    let mut parallel: BTreeMap<&str, (Vec<String>, Vec<String>)> = BTreeMap::new();
    for j in urdf.joints.iter().filter(driven) {
        if j.joint_type == JointType::Prismatic && leaf(j) {
            let entry = parallel.entry(j.parent.link.as_str()).or_default();
            entry.0.push(j.name.clone());
            entry.1.push(j.name.clone());
            for f in followers(&j.name) {
                if f.joint_type == JointType::Prismatic && f.parent.link == j.parent.link {
                    entry.1.push(f.name.clone());
                }
            }
        }
    }
    let found = parallel
        .into_iter()
        .find(|(_, (_, moved))| moved.len() == 2)
        .map(|(palm, (listed, moved))| (GripperKind::Parallel, palm.to_string(), listed, moved));
    let linkage = || {
        urdf.joints.iter().filter(driven).find_map(|j| {
            let f = followers(&j.name);
            (j.joint_type == JointType::Revolute && f.len() >= 3).then(|| {
                let mut moved = vec![j.name.clone()];
                moved.extend(f.iter().map(|f| f.name.clone()));
                (
                    GripperKind::Linkage,
                    j.parent.link.clone(),
                    vec![j.name.clone()],
                    moved,
                )
            })
        })
    };
    let path_to = |link: &str| -> Vec<&urdf_rs::Joint> {
        let mut path = Vec::new();
        let mut at = link;
        while let Some(j) = by_child.get(at) {
            path.push(*j);
            at = &j.parent.link;
        }
        path.reverse();
        path
    };
    let (gripper, palm, gripper_joints, finger_joints) = match found.or_else(linkage) {
        Some(g) => g,
        None => {
            // No gripper: the arm ends at the link with the most driven joints above it.
            let end = urdf
                .links
                .iter()
                .max_by_key(|l| {
                    let path = path_to(&l.name);
                    let count = path.iter().filter(|j| driven(j)).count();
                    (count, std::cmp::Reverse(path.len()))
                })
                .map(|l| l.name.clone())
                .unwrap_or_else(|| root.clone());
            (GripperKind::None, end, Vec::new(), Vec::new())
        }
    };
    let path = path_to(&palm);
    let arm_joints: Vec<String> = path
        .iter()
        .filter(|j| driven(j))
        .map(|j| j.name.clone())
        .collect();
    if arm_joints.is_empty() {
        return Err(format!(
            "no movable joint between the root `{root}` and `{palm}`"
        ));
    }
    // The flange: the link the hand is fixed to, when it is fixed past the last arm joint.
    let last = path.iter().rposition(driven).unwrap_or(path.len() - 1);
    let flange = match (by_child.get(palm.as_str()), gripper) {
        (Some(j), GripperKind::Parallel | GripperKind::Linkage)
            if j.joint_type == JointType::Fixed
                && path.iter().position(|p| p.name == j.name) > Some(last) =>
        {
            j.parent.link.clone()
        }
        _ => path[last].child.link.clone(),
    };
    Ok(Structure {
        root,
        arm_joints,
        palm,
        flange,
        gripper,
        gripper_joints,
        finger_joints,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fer_has_a_parallel_gripper_on_its_hand() {
        let urdf = crate::urdf_load::parse(crate::robot::PANDA_URDF).unwrap();
        let s = structure(&urdf).unwrap();
        assert_eq!(s.root, "base");
        assert_eq!(s.gripper, GripperKind::Parallel);
        assert_eq!(s.palm, "fer_hand");
        assert_eq!(s.flange, "fer_link8");
        assert_eq!(s.gripper_joints, ["fer_finger_joint1"]);
        assert_eq!(s.finger_joints, ["fer_finger_joint1", "fer_finger_joint2"]);
        assert_eq!(s.arm_joints.len(), 7);
    }

    #[test]
    fn a_linkage_gripper_and_an_arm_without_one_are_told_apart() {
        let knuckle = r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
            <link name="k1"/><link name="k2"/><link name="k3"/><link name="k4"/>
            <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
              <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
            <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 1 0"/>
              <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
            <joint name="k" type="revolute"><parent link="c"/><child link="k1"/><axis xyz="0 1 0"/>
              <limit lower="0" upper="0.8" velocity="1" effort="1"/></joint>
            <joint name="m2" type="revolute"><parent link="c"/><child link="k2"/><axis xyz="0 1 0"/>
              <limit lower="-0.8" upper="0" velocity="1" effort="1"/><mimic joint="k" multiplier="-1"/></joint>
            <joint name="m3" type="revolute"><parent link="c"/><child link="k3"/><axis xyz="0 1 0"/>
              <limit lower="0" upper="0.8" velocity="1" effort="1"/><mimic joint="k"/></joint>
            <joint name="m4" type="revolute"><parent link="k1"/><child link="k4"/><axis xyz="0 1 0"/>
              <limit lower="-0.8" upper="0" velocity="1" effort="1"/><mimic joint="k" multiplier="-1"/></joint>
            </robot>"#;
        let s = structure(&crate::urdf_load::parse(knuckle).unwrap()).unwrap();
        assert_eq!(s.gripper, GripperKind::Linkage);
        assert_eq!((s.palm.as_str(), s.flange.as_str()), ("c", "c"));
        assert_eq!(s.gripper_joints, ["k"]);
        assert_eq!(s.finger_joints.len(), 4);
        assert_eq!(s.arm_joints, ["j1", "j2"]);
        let bare = knuckle.replace(
            r#"type="revolute"><parent link="c"/>"#,
            r#"type="fixed"><parent link="c"/>"#,
        );
        let s = structure(&crate::urdf_load::parse(&bare).unwrap()).unwrap();
        assert_eq!(s.gripper, GripperKind::None);
        assert_eq!(s.arm_joints, ["j1", "j2"]);
    }
}
