//! How a parallel gripper's squeeze seats an object between its pads, read by the planner's
//! model of the held object and by the simulation's grasp alike.
//!
//! Two flat pads closing with tens of newtons on an object turn it until what they bear on lies
//! flat against them: a box's face, the side of a lying cylinder. An object grasped a few
//! degrees off (the hand was aimed at a perceived pose, the object stands at its true one) is
//! therefore held square in the hand, not turned as it was found. The turn modelled is the one
//! about the hand's approach axis (TCP z), through the point between the pads: it slides the
//! object on what it rests on without lifting or sinking it when the hand comes from above.
//! A turn about the closing axis (TCP y) is not undone (friction holds the object in it). A
//! tilt about the third axis (TCP x) is undone for a cylinder the pads hold by its side with
//! its axis along the approach (a bottle grasped from above): a pad that touches first pushes
//! its top over, and two flat pads bear on a cylinder's side only when its axis lies in their
//! planes, so the squeeze stands it back up (its base, which the push had tipped onto its
//! rim, comes up off the support by a millimetre or so). For a box the pads' faces already
//! lie flat on it after the turn about z, and the tilt is left to the support it rests on.
//!
//! The frame is the TCP's: the fingers close along its y axis and approach along z, as for the
//! Franka Hand.

use akl_scene::Shape;
use akl_tsr::nalgebra::{UnitQuaternion, Vector3};
use akl_tsr::Pose;

/// Largest turn (radians) the squeeze is credited with: 0.1 rad (5.7°), above the 4σ of the
/// perception error (4°) that leaves objects turned in the hand. Further off, a pad meets an
/// edge or corner first and what happens depends on friction the simulation does not model,
/// so the object stays as it was grasped.
pub(crate) const MAX_SQUARING: f64 = 0.1;

/// The turn (radians, about TCP z) that lays `shape`, at `in_tcp` in the TCP frame, flat on the
/// pads; 0 when the shape is round about that axis or the turn would exceed 0.1 rad (`MAX_SQUARING`).
pub fn squaring_turn(shape: &Shape, in_tcp: &Pose) -> f64 {
    let r = in_tcp.rotation.to_rotation_matrix();
    let axis = |k: usize| -> Vector3<f64> { r.matrix().column(k).into_owned() };
    let turn = match shape {
        // A mesh is held as it was grasped: which of its faces the pads bear on is not known.
        Shape::Sphere { .. } | Shape::Mesh { .. } => None,
        Shape::Box { .. } => {
            let facing = (0..3)
                .map(axis)
                .max_by(|a, b| a.y.abs().total_cmp(&b.y.abs()))
                .unwrap_or_else(Vector3::y);
            face_onto_pads(&facing)
        }
        Shape::Cylinder { .. } | Shape::Capsule { .. } => {
            let d = axis(2);
            if d.y.abs() >= std::f64::consts::FRAC_1_SQRT_2 {
                // The pads bear on the end faces.
                face_onto_pads(&d)
            } else {
                side_onto_pads(&d)
            }
        }
    };
    turn.filter(|t| t.abs() <= MAX_SQUARING).unwrap_or(0.0)
}

/// The tilt (radians, about TCP x) that stands a cylinder held by its side, its axis along the
/// approach, back into the pads' planes; 0 for other shapes and grasps, and when the tilt would
/// exceed [`MAX_SQUARING`].
pub(crate) fn straightening_tilt(shape: &Shape, in_tcp: &Pose) -> f64 {
    let (Shape::Cylinder { .. } | Shape::Capsule { .. }) = shape else {
        return 0.0;
    };
    let d = in_tcp.rotation * Vector3::z();
    if d.z.abs() < std::f64::consts::FRAC_1_SQRT_2 {
        return 0.0;
    }
    // Rx(φ) d has no y component when tan φ = d.y / d.z.
    let tilt = (d.y / d.z).atan();
    if tilt.abs() <= MAX_SQUARING {
        tilt
    } else {
        0.0
    }
}

/// `in_tcp` turned by [`squaring_turn`] about the TCP's z axis and stood up by
/// `straightening_tilt` about its x axis: the pose the squeeze leaves the object at in the
/// hand.
pub fn squared_in_hand(shape: &Shape, in_tcp: &Pose) -> Pose {
    let turn = squaring_turn(shape, in_tcp);
    let turned = if turn == 0.0 {
        *in_tcp
    } else {
        Pose::from_parts(
            Default::default(),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn),
        ) * in_tcp
    };
    let tilt = straightening_tilt(shape, &turned);
    if tilt == 0.0 {
        return turned;
    }
    Pose::from_parts(
        Default::default(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), tilt),
    ) * turned
}

/// How far (below this, radians) an axis may lean out of the pads' plane and still count as
/// lying in it; a cylinder seen end-on from the approach (its axis along TCP z) is round about
/// that axis and needs no turn.
const ROUND: f64 = 1e-6;

/// The turn about z that brings face normal `n` onto the closing axis (±y).
fn face_onto_pads(n: &Vector3<f64>) -> Option<f64> {
    (n.xy().norm() > ROUND).then(|| (n.x / n.y).atan())
}

/// The turn about z that brings a lying cylinder's axis `d` into the pads' plane (y = 0).
fn side_onto_pads(d: &Vector3<f64>) -> Option<f64> {
    (d.xy().norm() > ROUND).then(|| (-d.y / d.x).atan())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pose(yaw: f64) -> Pose {
        Pose::from_parts(
            Vector3::new(0.002, 0.0, 0.01).into(),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    }

    fn closing_component(shape: &Shape, p: &Pose) -> f64 {
        let r = p.rotation.to_rotation_matrix();
        match shape {
            Shape::Cylinder { .. } => r.matrix().column(2).y.abs(),
            _ => {
                1.0 - (0..3)
                    .map(|k| r.matrix().column(k).y.abs())
                    .fold(0.0, f64::max)
            }
        }
    }

    const BOX: Shape = Shape::Box {
        size: [0.05, 0.05, 0.08],
    };
    const PIPE: Shape = Shape::Cylinder {
        radius: 0.025,
        length: 0.3,
    };

    proptest! {
        #[test]
        fn a_small_turn_is_undone_and_nothing_else_changes(
            yaw in -0.09f64..0.09,
            pitch in -0.3f64..0.3,
            quarter in 0..4i32,
        ) {
            let spin = f64::from(quarter) * std::f64::consts::FRAC_PI_2;
            for shape in [BOX, PIPE] {
                // The pipe lies across the pads (axis along TCP x), the box any quarter turn.
                let base = match shape {
                    Shape::Cylinder { .. } => UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0),
                    _ => UnitQuaternion::from_euler_angles(0.0, 0.0, spin),
                };
                // Turned about the closing axis (friction holds that), otherwise square.
                let square = Pose::from_parts(
                    Vector3::new(0.0, 0.0, 0.01).into(),
                    UnitQuaternion::from_euler_angles(0.0, pitch, 0.0) * base,
                );
                let turned = Pose::from_parts(Default::default(), UnitQuaternion::from_euler_angles(0.0, 0.0, yaw)) * square;
                let seated = squared_in_hand(&shape, &turned);
                prop_assert!(closing_component(&shape, &seated) < 1e-9);
                // Only a turn about z: the height along the approach is kept.
                prop_assert!((seated.translation.z - turned.translation.z).abs() < 1e-12);
                prop_assert!((squaring_turn(&shape, &turned) + yaw).abs() < 1e-9, "{shape:?}");
            }
        }
    }

    #[test]
    fn a_bottle_pushed_over_by_the_first_pad_is_stood_up_between_the_pads() {
        let bottle = Shape::Cylinder {
            radius: 0.025,
            length: 0.16,
        };
        // Grasped from above near its top: its axis along the approach, tipped towards a pad.
        let upright = Pose::from_parts(
            Vector3::new(0.0, 0.0, 0.055).into(),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        );
        let tipped = Pose::from_parts(
            Default::default(),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.045),
        ) * upright;
        assert!((straightening_tilt(&bottle, &tipped) + 0.045).abs() < 1e-9);
        let seated = squared_in_hand(&bottle, &tipped);
        assert!(
            (seated.rotation * Vector3::z()).y.abs() < 1e-9,
            "{seated:?}"
        );
        assert!((seated.translation.vector - upright.translation.vector).norm() < 1e-9);
        // A lying pipe and a box are not tilted.
        assert_eq!(straightening_tilt(&PIPE, &pose(0.0)), 0.0);
        assert_eq!(straightening_tilt(&BOX, &tipped), 0.0);
    }

    #[test]
    fn round_and_far_turned_objects_stay_as_grasped() {
        let sphere = Shape::Sphere { radius: 0.03 };
        let p = pose(0.05);
        assert_eq!(squared_in_hand(&sphere, &p), p);
        let standing = Shape::Cylinder {
            radius: 0.03,
            length: 0.1,
        };
        assert_eq!(squaring_turn(&standing, &pose(0.05)), 0.0);
        let far = pose(0.3);
        assert_eq!(squaring_turn(&BOX, &far), 0.0);
        assert_eq!(squared_in_hand(&BOX, &far), far);
    }
}
