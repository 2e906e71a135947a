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
use crate::parry_convert::{distance, object_shape, pose, robot_shape};
use crate::{Geometry, Robot, ShapeRole};
use akl_scene::Shape;
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// Share of the closing speed at which the fingers go on once one pad touches what they close
/// on: that pad pushes the object towards the other at half speed, so it slides to the middle
/// instead of being knocked over. The simulation closes so, and the planner gives a grasp the
/// time its centring takes.
pub const PUSH_SHARE: f64 = 0.5;

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
            lo[k] = lo[k].min(aabb.mins[k]);
            hi[k] = hi[k].max(aabb.maxs[k]);
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

/// Whether a gripper joint moves link `i`, which hangs from `palm`: one of the joints from
/// `palm` down to it is a gripper joint.
fn moved_below(robot: &Robot, mut i: usize, palm: usize) -> bool {
    let links = robot.links();
    loop {
        if robot.finger_joints().contains(&links[i].joint) {
            return true;
        }
        match links[i].parent {
            Some(p) if p != palm => i = p,
            _ => return false,
        }
    }
}

/// How far (radians) a linkage's fingertip may turn over the opening and still count as kept
/// parallel.
const PARALLEL_TOLERANCE: f64 = 0.01;

/// A linkage gripper's two fingertips and its knuckle link, when the gripper is one: the
/// listed gripper joint is revolute, and exactly two leaf links below the knuckle's parent
/// are moved by gripper joints (the Robotiq 2F-85's fingertips).
fn linkage_fingers(robot: &Robot) -> Result<Option<(usize, usize, usize)>, GripperError> {
    let links = robot.links();
    let listed = &robot.config().gripper.joints;
    let Some(knuckle) = (0..links.len()).find(|&i| {
        listed.contains(&links[i].joint) && matches!(links[i].motion, Motion::Revolute { .. })
    }) else {
        return Ok(None);
    };
    let palm = links[knuckle].parent.ok_or(GripperError::TwoHands)?;
    let tips: Vec<usize> = (0..links.len())
        .filter(|&i| !links.iter().any(|l| l.parent == Some(i)) && moved_below(robot, i, palm))
        .collect();
    // Each fingertip carries a pad; other moved leaves (a 2F-85's outer finger links) lie
    // nearer the palm: the tips are the two leaves farthest from it, fingers open.
    let poses = robot.link_poses(robot.ready(), robot.open_width());
    let mut tips: Vec<(f64, usize)> = tips
        .into_iter()
        .map(|i| {
            (
                (poses[palm].inverse() * poses[i]).translation.vector.norm(),
                i,
            )
        })
        .collect();
    tips.sort_by(|x, y| y.0.total_cmp(&x.0));
    let tips: Vec<usize> = tips.into_iter().map(|(_, i)| i).collect();
    // The linkage must keep the tips parallel (their pads face each other at every opening).
    let shut = robot.link_poses(robot.ready(), 0.0);
    for &tip in tips.iter().take(2) {
        let turn = |p: &[Pose]| (p[palm].inverse() * p[tip]).rotation;
        if turn(&poses).angle_to(&turn(&shut)) > PARALLEL_TOLERANCE {
            return Err(GripperError::NotParallel(links[tip].name.clone()));
        }
    }
    match tips[..] {
        [a, b, ..] => Ok(Some((a, b, knuckle))),
        _ => Err(GripperError::LinkageTips(
            tips.iter().map(|&i| links[i].name.clone()).collect(),
        )),
    }
}

/// For a linkage gripper, the knuckle angle for each gap between the pads' inner faces,
/// `[gap, angle]` by increasing gap, over the knuckle's range (65 angles); `None` for other
/// grippers. Measured on `robot` before its map is set (its opening input is the angle).
pub(crate) fn linkage_width_map(robot: &Robot) -> Option<Vec<[f64; 2]>> {
    let (_, _, knuckle) = linkage_fingers(robot).ok()??;
    let hand = HandModel::build(robot).ok()?;
    let joint = &robot.links()[knuckle].joint;
    let limit = &robot.urdf().joints.iter().find(|j| j.name == *joint)?.limit;
    let palm = hand.palm_link;
    let face = |poses: &[Pose], f: &Finger| {
        (poses[palm].inverse() * poses[f.link])
            .transform_point(&Point3::from(f.face_centre()))
            .coords
    };
    // The gap is measured along the line between the faces where they are farthest apart.
    let apart = |angle: f64| {
        let poses = robot.link_poses(robot.ready(), angle);
        face(&poses, &hand.fingers[1]) - face(&poses, &hand.fingers[0])
    };
    let (lower, upper) = (apart(limit.lower), apart(limit.upper));
    let widest = if lower.norm() >= upper.norm() {
        lower
    } else {
        upper
    };
    let along = widest.try_normalize(1e-9)?;
    let mut map: Vec<[f64; 2]> = (0..=64)
        .map(|k| {
            let angle = limit.lower + (limit.upper - limit.lower) * f64::from(k) / 64.0;
            let poses = robot.link_poses(robot.ready(), angle);
            let gap = (face(&poses, &hand.fingers[1]) - face(&poses, &hand.fingers[0])).dot(&along);
            [gap.max(0.0), angle]
        })
        .collect();
    map.sort_by(|x, y| x[0].total_cmp(&y[0]));
    map.dedup_by(|x, y| x[0] <= y[0]);
    (map.len() >= 2).then_some(map)
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
    /// The links a linkage gripper moves as it closes, but for the two fingertips (the
    /// 2F-85's knuckles, finger links and inner knuckles); none for prismatic fingers. The
    /// simulation gives them all their collision shapes, and the planner keeps their closing
    /// sweep clear of what a grasp closes on (`closing_clearance`).
    pub linkage: Vec<usize>,
}

impl HandModel {
    /// The hand of `robot`, or `None` when the simulation cannot drive its gripper: it drives
    /// two prismatic fingers on one link or a linkage whose knuckle moves two fingertips, and
    /// [`Robot::load`] refuses any other gripper with a [`GripperError`] saying why.
    pub fn new(robot: &Robot) -> Option<HandModel> {
        HandModel::build(robot).ok()
    }

    /// The hand of `robot`, or why the simulation cannot drive its gripper: it drives two
    /// prismatic fingers on one link, each with a primitive collision element to grasp with,
    /// or a linkage whose knuckle moves two fingertips (pads: their collision meshes' bounds).
    pub(crate) fn build(robot: &Robot) -> Result<HandModel, GripperError> {
        let links = robot.links();
        let linkage = linkage_fingers(robot)?;
        let (a, b, palm_link) = match linkage {
            Some((a, b, knuckle)) => (a, b, links[knuckle].parent.ok_or(GripperError::TwoHands)?),
            None => {
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
                (a, b, palm_link)
            }
        };
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
        let (origin_a, origin_b) = (in_palm(a).translation.vector, in_palm(b).translation.vector);
        // A linkage closes its fingertips along the line between them (the pads stay
        // parallel as the linkage turns); prismatic fingers along their axis.
        let closing = match linkage {
            Some(_) => (origin_b - origin_a)
                .try_normalize(1e-9)
                .ok_or(GripperError::TwoHands)?,
            None => axis(a).ok_or(GripperError::TwoHands)?,
        };
        let inward = |i: usize, from: &Vector3<f64>, to: &Vector3<f64>| {
            let d = (to - from).dot(&closing).signum() * closing;
            in_palm(i).rotation.inverse() * d
        };
        let (in_a, in_b) = (
            inward(a, &origin_a, &origin_b),
            inward(b, &origin_b, &origin_a),
        );
        // The pad: the element whose bounds reach furthest inward; for a fingertip with
        // meshes only (a linkage's), the bounds of its collision meshes.
        let pad = |i: usize, inward: &Vector3<f64>| -> Option<(usize, LocalBox)> {
            let primitive = shapes(i)
                .iter()
                .enumerate()
                .filter_map(|(k, s)| {
                    let (lo, hi) = bounds(std::slice::from_ref(s))?;
                    let b = LocalBox::from_bounds(lo, hi);
                    Some((k, b, b.centre.dot(inward) + b.half.dot(&inward.abs())))
                })
                .max_by(|x, y| x.2.total_cmp(&y.2))
                .map(|(k, b, _)| (k, b));
            // A fingertip's pad is its distal half: the half of its bounds farther from the
            // palm along the tip frame's axis that points most away from it.
            let meshes = || {
                let (mut lo, mut hi) = mesh_bounds(robot, i)?;
                let out = in_palm(i).rotation.inverse() * in_palm(i).translation.vector;
                let k = out.iamax();
                let middle = 0.5 * (lo[k] + hi[k]);
                if out[k] > 0.0 {
                    lo[k] = middle;
                } else {
                    hi[k] = middle;
                }
                Some((usize::MAX, LocalBox::from_bounds(lo, hi)))
            };
            primitive.or_else(|| linkage.and_then(|_| meshes()))
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
        // The palm ends at the plane of the finger joints (a linkage's knuckles).
        let mount = match linkage {
            Some((_, _, knuckle)) => links[knuckle].origin.translation.vector,
            None => links[a].origin.translation.vector,
        };
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
        // The rest of the linkage: links below the palm that a gripper joint moves.
        let linkage = match linkage {
            Some(_) => (0..links.len())
                .filter(|&i| i != a && i != b && moved_below(robot, i, palm_link))
                .collect(),
            None => Vec::new(),
        };
        Ok(HandModel {
            fingers,
            palm_link,
            palm,
            linkage,
        })
    }

    /// The finger with robot link index `link`.
    pub fn finger(&self, link: usize) -> Option<&Finger> {
        self.fingers.iter().find(|f| f.link == link)
    }

    /// The boxes of the hand as (link, geometry, pose in the link frame): the palm and each
    /// pad.
    pub(crate) fn boxes(&self) -> Vec<(usize, Geometry, Pose)> {
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

/// The furthest (metres) a point of a linkage moves between two consecutive openings at which
/// its closing is checked ([`HandModel::closing_openings`]).
pub(crate) const SWEEP_STEP: f64 = 0.001;

/// At most this many intervals between the openings at which a closing is checked.
const MAX_SWEEP_INTERVALS: usize = 1024;

/// How close a linkage comes to an object while the gripper closes on it
/// ([`closing_clearance`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ClosingClearance {
    /// The linkage link that comes closest (robot link index).
    pub link: usize,
    /// The least distance between it and the object over the whole closing (metres; 0 or less
    /// when they meet).
    pub clearance: f64,
}

impl HandModel {
    /// The collision shapes of the linkage ([`HandModel::linkage`]) as (link, geometry, pose
    /// in the link frame): every shape of those links, as the simulation has them.
    pub(crate) fn linkage_shapes<'r>(&self, robot: &'r Robot) -> Vec<(usize, &'r Geometry, Pose)> {
        self.linkage
            .iter()
            .flat_map(|&i| {
                robot.links()[i]
                    .shapes
                    .iter()
                    .map(move |s| (i, &s.geometry, s.origin))
            })
            .collect()
    }

    /// The openings, from `from` down to `to`, at which a closing with the arm at `q` is
    /// checked, and the furthest any point of the linkage moves between two consecutive ones
    /// (metres): evenly spaced, as many as it takes for that to be at most [`SWEEP_STEP`] (at
    /// most 1024 intervals). A rigid motion moves no point of a shape further than it moves
    /// one of the corners of the shape's bounding box, so the corners bound every point.
    pub(crate) fn closing_openings(
        &self,
        robot: &Robot,
        q: &[f64],
        from: f64,
        to: f64,
    ) -> (Vec<f64>, f64) {
        let corners: Vec<(usize, Point3<f64>)> = self
            .linkage_shapes(robot)
            .into_iter()
            .flat_map(|(link, geometry, origin)| {
                let (shape, fix) = robot_shape(geometry, 0.0);
                let aabb = shape.compute_aabb(&pose(&Pose::identity()));
                let (lo, hi) = (aabb.mins, aabb.maxs);
                let local = origin * fix;
                (0..8).map(move |k| {
                    let pick = |bit: usize, l: f64, h: f64| if k >> bit & 1 == 0 { l } else { h };
                    let c = Point3::new(
                        pick(0, lo.x, hi.x),
                        pick(1, lo.y, hi.y),
                        pick(2, lo.z, hi.z),
                    );
                    (link, local * c)
                })
            })
            .collect();
        let mut intervals = 8;
        loop {
            let openings: Vec<f64> = (0..=intervals)
                .map(|k| match k {
                    // Both ends exactly: the last is the grasp itself.
                    k if k == intervals => to,
                    k => from + (to - from) * k as f64 / intervals as f64,
                })
                .collect();
            let placed: Vec<Vec<Point3<f64>>> = openings
                .iter()
                .map(|&w| {
                    let poses = robot.link_poses(q, w);
                    corners.iter().map(|(link, c)| poses[*link] * c).collect()
                })
                .collect();
            let step = placed
                .windows(2)
                .flat_map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| (b - a).norm()))
                .fold(0.0, f64::max);
            if step <= SWEEP_STEP || intervals >= MAX_SWEEP_INTERVALS {
                return (openings, step);
            }
            intervals *= 2;
        }
    }
}

/// How close the linkage of `hand` comes to `object` at `object_pose` (in the robot's base
/// frame) while the gripper closes from its full opening down to `width`, the arm standing at
/// `q`: the least distance found at the openings of [`HandModel::closing_openings`], less half
/// the furthest a point moves between two of them, so that no opening in between comes closer.
/// `None` when the gripper has no linkage (prismatic fingers: only their pads move).
///
/// The pads close on what they grasp, and the contact rules let the hand touch it; a
/// linkage's other parts (the 2F-85's inner knuckles swing in above the pads as it closes)
/// must not press it, which the planner checks with this before it takes a grasp.
pub(crate) fn closing_clearance(
    robot: &Robot,
    hand: &HandModel,
    q: &[f64],
    width: f64,
    object: &Shape,
    object_pose: &Pose,
) -> Option<ClosingClearance> {
    let shapes = hand.linkage_shapes(robot);
    if shapes.is_empty() {
        return None;
    }
    let bodies: Vec<(usize, SharedShape, Pose)> = shapes
        .into_iter()
        .map(|(link, geometry, origin)| {
            let (shape, fix) = robot_shape(geometry, 0.0);
            (link, shape, origin * fix)
        })
        .collect();
    let (object_shape, fix) = object_shape(object, 0.0);
    let placed_object = object_pose * fix;
    let (openings, step) = hand.closing_openings(robot, q, robot.open_width(), width);
    let mut closest: Option<ClosingClearance> = None;
    for &w in &openings {
        let poses = robot.link_poses(q, w);
        for (link, shape, local) in &bodies {
            let d = distance(
                shape,
                &(poses[*link] * local),
                &object_shape,
                &placed_object,
            )
            .unwrap_or(0.0)
                - 0.5 * step;
            if closest.is_none_or(|c| d < c.clearance) {
                closest = Some(ClosingClearance {
                    link: *link,
                    clearance: d,
                });
            }
        }
    }
    closest
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
