//! The gripper as bodies: the palm and the two finger pads, derived from the URDF.
//!
//! The simulation grasps with these (a palm that ends where the fingers are mounted, two flat
//! pads that close on what is between them), and the planner's collision model of the hand
//! holds them besides the URDF's own shapes, so whatever the simulated hand touches, the
//! planner kept clear (the boxes may reach past the link's own collision shapes). The URDF
//! shapes fill the space between the fingers, so that planning keeps that space free.
//! Both are derived from the URDF, so another two-finger robot works the same way:
//! - each pad is the bounding box of the finger's URDF element that reaches furthest towards
//!   the other finger (for the Panda, Franka's 17.5 × 15.2 × 18.5 mm rubber tip, 36–54.5 mm
//!   along the finger, its inner face on the finger's inner side); the finger's other
//!   elements (the Panda's screw mount, carriage sledge and diagonal finger) are simulated as
//!   they are;
//! - the palm is the bounding box of the hand link's URDF primitives (of its collision meshes
//!   when it has none, as Franka's hand), cut at the plane where the finger joints sit (for
//!   the Panda, 58.4 mm below the flange).

use crate::error::GripperError;
use crate::fk::Motion;
use crate::meshes::MeshRole;
use crate::parry_convert::{pose, robot_shape};
use crate::{Geometry, Robot, ShapeRole};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;

/// An axis-aligned box in some frame: its centre and half extents.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalBox {
    /// Centre in the frame.
    pub centre: Vector3<f64>,
    /// Half extents along the frame's axes.
    pub half: Vector3<f64>,
}

impl LocalBox {
    fn from_bounds(lo: Vector3<f64>, hi: Vector3<f64>) -> LocalBox {
        LocalBox {
            centre: 0.5 * (lo + hi),
            half: 0.5 * (hi - lo),
        }
    }

    /// The box as a collision geometry placed in the frame.
    pub fn geometry(&self) -> (Geometry, Pose) {
        (
            Geometry::Box {
                size: [2.0 * self.half.x, 2.0 * self.half.y, 2.0 * self.half.z],
            },
            Pose::translation(self.centre.x, self.centre.y, self.centre.z),
        )
    }
}

/// The bounds, in the link frame, of a set of URDF shapes.
fn bounds(shapes: &[(Geometry, Pose)]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for (geometry, origin) in shapes {
        let (shape, fix) = robot_shape(geometry, 0.0);
        let aabb = shape.compute_aabb(&pose(&(origin * fix)));
        for k in 0..3 {
            lo[k] = lo[k].min(f64::from(aabb.mins[k]));
            hi[k] = hi[k].max(f64::from(aabb.maxs[k]));
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The bounds, in the link frame, of a link's collision meshes.
fn mesh_bounds(robot: &Robot, link: usize) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    let meshes = robot
        .meshes()
        .iter()
        .filter(|m| m.link == link && m.role == MeshRole::Collision);
    for v in meshes.flat_map(|m| &m.mesh.vertices) {
        lo = lo.inf(&v.coords);
        hi = hi.sup(&v.coords);
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// One finger: its link, its pad in the link frame, and which way its pad faces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Finger {
    /// Robot link index.
    pub link: usize,
    /// The pad, in the finger link's frame.
    pub pad: LocalBox,
    /// Index, among the finger link's URDF elements, of the one the pad is made from.
    pub pad_element: usize,
    /// Unit direction (finger link frame) from this pad towards the other.
    pub inward: Vector3<f64>,
}

impl Finger {
    /// Centre of the pad's inner face, in the finger link's frame.
    pub fn face_centre(&self) -> Vector3<f64> {
        let along = self.pad.half.dot(&self.inward.abs());
        self.pad.centre + along * self.inward
    }
}

/// The simulated hand: palm and pads, derived from the robot's URDF.
#[derive(Debug, Clone, PartialEq)]
pub struct HandModel {
    /// The two fingers.
    pub fingers: [Finger; 2],
    /// Robot link index of the link the fingers are mounted on (the hand).
    pub palm_link: usize,
    /// The palm, in the hand link's frame.
    pub palm: Option<LocalBox>,
}

impl HandModel {
    /// The hand of `robot`, or `None` when the simulation cannot drive its gripper (see
    /// [`HandModel::build`] for why).
    pub fn new(robot: &Robot) -> Option<HandModel> {
        HandModel::build(robot).ok()
    }

    /// The hand of `robot`, or why the simulation cannot drive its gripper: it drives two
    /// prismatic fingers on one link, each with a primitive collision element to grasp with.
    pub fn build(robot: &Robot) -> Result<HandModel, GripperError> {
        let links = robot.links();
        let finger_links: Vec<usize> = (0..links.len())
            .filter(|&i| robot.finger_joints().contains(&links[i].joint))
            .collect();
        if let Some(&i) = finger_links
            .iter()
            .find(|&&i| !matches!(links[i].motion, Motion::Prismatic { .. }))
        {
            return Err(GripperError::NotPrismatic(links[i].joint.clone()));
        }
        let [a, b] = finger_links[..] else {
            return Err(GripperError::FingerCount(robot.finger_joints().to_vec()));
        };
        let palm_link = links[a].parent.ok_or(GripperError::TwoHands)?;
        if links[b].parent != Some(palm_link) {
            return Err(GripperError::TwoHands);
        }
        // The URDF's own primitives: the hulls that enclose meshes reach past the real link.
        let shapes = |i: usize| -> Vec<(Geometry, Pose)> {
            links[i]
                .shapes
                .iter()
                .filter(|s| s.role == ShapeRole::Exact)
                .map(|s| (s.geometry.clone(), s.origin))
                .collect()
        };
        // The fingers at full opening, in the palm's frame: the closing axis, and which way
        // along it each finger's frame lies from the other's.
        let open = robot.open_width();
        let poses = robot.link_poses(robot.ready(), open);
        let in_palm = |i: usize| poses[palm_link].inverse() * poses[i];
        let axis = |i: usize| match links[i].motion {
            Motion::Prismatic { axis, .. } => Some(links[i].origin.rotation * axis.into_inner()),
            _ => None,
        };
        let closing = axis(a).ok_or(GripperError::TwoHands)?;
        let (origin_a, origin_b) = (in_palm(a).translation.vector, in_palm(b).translation.vector);
        let inward = |i: usize, from: &Vector3<f64>, to: &Vector3<f64>| {
            let d = (to - from).dot(&closing).signum() * closing;
            in_palm(i).rotation.inverse() * d
        };
        let (in_a, in_b) = (
            inward(a, &origin_a, &origin_b),
            inward(b, &origin_b, &origin_a),
        );
        // The pad: the element whose bounds reach furthest inward.
        let pad = |i: usize, inward: &Vector3<f64>| -> Option<(usize, LocalBox)> {
            shapes(i)
                .iter()
                .enumerate()
                .filter_map(|(k, s)| {
                    let (lo, hi) = bounds(std::slice::from_ref(s))?;
                    let b = LocalBox::from_bounds(lo, hi);
                    Some((k, b, b.centre.dot(inward) + b.half.dot(&inward.abs())))
                })
                .max_by(|x, y| x.2.total_cmp(&y.2))
                .map(|(k, b, _)| (k, b))
        };
        let no_pad = |i: usize| GripperError::NoPad(links[i].name.clone());
        let (element_a, pad_a) = pad(a, &in_a).ok_or_else(|| no_pad(a))?;
        let (element_b, pad_b) = pad(b, &in_b).ok_or_else(|| no_pad(b))?;
        let fingers = [
            Finger {
                link: a,
                pad: pad_a,
                pad_element: element_a,
                inward: in_a,
            },
            Finger {
                link: b,
                pad: pad_b,
                pad_element: element_b,
                inward: in_b,
            },
        ];
        // The palm ends at the plane of the finger joints.
        let mount = links[a].origin.translation.vector;
        let out = mount.iamax();
        let sign = mount[out].signum();
        let palm_bounds = bounds(&shapes(palm_link)).or_else(|| mesh_bounds(robot, palm_link));
        let palm = palm_bounds.and_then(|(mut lo, mut hi)| {
            if sign > 0.0 {
                hi[out] = hi[out].min(mount[out]);
            } else {
                lo[out] = lo[out].max(mount[out]);
            }
            (lo[out] < hi[out]).then(|| LocalBox::from_bounds(lo, hi))
        });
        Ok(HandModel {
            fingers,
            palm_link,
            palm,
        })
    }

    /// The finger with robot link index `link`.
    pub fn finger(&self, link: usize) -> Option<&Finger> {
        self.fingers.iter().find(|f| f.link == link)
    }

    /// The boxes of the hand as (link, geometry, pose in the link frame): the palm and each
    /// pad.
    pub fn boxes(&self) -> Vec<(usize, Geometry, Pose)> {
        let palm = self.palm.map(|p| (self.palm_link, p));
        let pads = self.fingers.iter().map(|f| (f.link, f.pad));
        palm.into_iter()
            .chain(pads)
            .map(|(link, b)| {
                let (geometry, origin) = b.geometry();
                (link, geometry, origin)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_panda_pads_face_each_other_and_the_palm_stops_at_the_fingers() {
        let robot = Robot::panda().unwrap();
        let hand = HandModel::new(&robot).unwrap();
        for f in &hand.fingers {
            // Franka's rubber tip: 17.5 × 15.2 × 18.5 mm, 36–54.5 mm along the finger, the
            // last of the finger's four elements.
            assert!(
                (f.pad.half - Vector3::new(0.00875, 0.0076, 0.00925)).norm() < 1e-5,
                "{f:?}"
            );
            assert!((f.pad.centre.z - 0.04525).abs() < 1e-6, "{f:?}");
            assert_eq!(f.pad_element, 3);
            assert!(f.inward.norm() > 0.999);
            // The inner face lies on the finger joint's axis line (the URDF finger's inner side).
            assert!(f.face_centre().y.abs() < 1e-4, "{:?}", f.face_centre());
        }
        // Each finger's frame has its inner side towards -y (the FER turns the right finger
        // half a turn about z); in the palm's frame the two face each other.
        let poses = robot.link_poses(robot.ready(), robot.open_width());
        let in_palm =
            |f: &Finger| (poses[hand.palm_link].inverse() * poses[f.link]).rotation * f.inward;
        for f in &hand.fingers {
            assert!(f.inward.dot(&Vector3::y()) < -0.99, "{f:?}");
        }
        assert!(in_palm(&hand.fingers[0]).dot(&in_palm(&hand.fingers[1])) < -0.99);
        let palm = hand.palm.unwrap();
        assert!(
            (palm.centre.z + palm.half.z - 0.0584).abs() < 1e-5,
            "{palm:?}"
        );
        assert!(palm.half.y > 0.08, "{palm:?}");
    }
}
