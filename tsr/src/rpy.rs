//! Roll-pitch-yaw angles with R = Rz(yaw)·Ry(pitch)·Rx(roll), the TSR convention.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use std::f64::consts::PI;

/// The rotation for roll, pitch and yaw (radians), R = Rz(yaw)·Ry(pitch)·Rx(roll).
pub fn rotation_from_rpy(rpy: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
}

/// Roll, pitch and yaw of a rotation, with pitch in [-π/2, π/2] and roll, yaw in (-π, π].
///
/// Stays exact near pitch = ±π/2 (gimbal lock): yaw is read from the first column and roll
/// from what is left once yaw and pitch are undone, so the triple always reproduces the
/// rotation to machine precision even where yaw alone is ill-conditioned.
pub fn rpy_from_rotation(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let m: Matrix3<f64> = rotation.to_rotation_matrix().into_inner();
    let cos_pitch = m[(0, 0)].hypot(m[(1, 0)]);
    let pitch = (-m[(2, 0)]).atan2(cos_pitch);
    let yaw = m[(1, 0)].atan2(m[(0, 0)]);
    let rest = Rotation3::from_euler_angles(0.0, pitch, yaw).inverse()
        * Rotation3::from_matrix_unchecked(m);
    let r = rest.matrix();
    let roll = r[(2, 1)].atan2(r[(1, 1)]);
    [roll, pitch, yaw]
}

/// Wraps an angle into (-π, π].
pub(crate) fn wrap_angle(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI {
        w + 2.0 * PI
    } else {
        w
    }
}

/// The roll-pitch-yaw triple equivalent to `rpy` across the pitch fold:
/// (r + π, π − p, y + π) describes the same rotation.
pub(crate) fn folded_rpy(rpy: [f64; 3]) -> [f64; 3] {
    [
        wrap_angle(rpy[0] + PI),
        wrap_angle(PI - rpy[1]),
        wrap_angle(rpy[2] + PI),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rotation_error(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
        a.angle_to(b)
    }

    proptest! {
        #[test]
        fn rpy_round_trips_any_rotation(r in -PI..PI, p in -PI / 2.0..PI / 2.0, y in -PI..PI) {
            let q = rotation_from_rpy([r, p, y]);
            let back = rotation_from_rpy(rpy_from_rotation(&q));
            prop_assert!(rotation_error(&q, &back) < 1e-9);
        }

        #[test]
        fn rpy_round_trips_near_gimbal_lock(r in -PI..PI, e in -1e-7..1e-7f64, y in -PI..PI, sign in prop::bool::ANY) {
            let p = if sign { PI / 2.0 - e.abs() } else { -PI / 2.0 + e.abs() };
            let q = rotation_from_rpy([r, p, y]);
            let back = rotation_from_rpy(rpy_from_rotation(&q));
            prop_assert!(rotation_error(&q, &back) < 1e-9);
        }

        #[test]
        fn recovers_the_angles_away_from_gimbal_lock(r in -3.0..3.0, p in -1.5..1.5, y in -3.0..3.0f64) {
            let got = rpy_from_rotation(&rotation_from_rpy([r, p, y]));
            prop_assert!((got[0] - r).abs() < 1e-9);
            prop_assert!((got[1] - p).abs() < 1e-9);
            prop_assert!((got[2] - y).abs() < 1e-9);
        }

        #[test]
        fn the_folded_triple_is_the_same_rotation(r in -PI..PI, p in -PI / 2.0..PI / 2.0, y in -PI..PI) {
            let a = rotation_from_rpy([r, p, y]);
            let b = rotation_from_rpy(folded_rpy([r, p, y]));
            prop_assert!(rotation_error(&a, &b) < 1e-9);
        }

        #[test]
        fn wrapped_angles_lie_in_the_half_open_interval(a in -100.0..100.0f64) {
            let w = wrap_angle(a);
            prop_assert!(w > -PI && w <= PI);
            prop_assert!(((w - a) / (2.0 * PI) - ((w - a) / (2.0 * PI)).round()).abs() < 1e-9);
        }
    }

    #[test]
    fn exact_gimbal_lock_round_trips() {
        for p in [PI / 2.0, -PI / 2.0] {
            let q = rotation_from_rpy([0.3, p, -1.1]);
            let back = rotation_from_rpy(rpy_from_rotation(&q));
            assert!(rotation_error(&q, &back) < 1e-9);
        }
    }
}
