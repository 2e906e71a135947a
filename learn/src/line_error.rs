//! The signal the straight-line detector reads (thesis Eq. 3.2): how far a point lies from
//! the line through the two before it. Shared by the online detector and its calibration.

use akl_tsr::nalgebra::Vector3;

/// Eq. 3.2: the distance of `c` from the line through `a` and `b` (0 when `a == b`).
pub(crate) fn line_error(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
    let u = b - a;
    let v = c - b;
    let len = u.norm();
    if len == 0.0 {
        return v.norm();
    }
    let along = v.dot(&u) / len;
    (v.norm_squared() - along * along).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn line_error_is_the_perpendicular_distance(
            ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in -1.0f64..1.0,
            ux in -1.0f64..1.0, uy in -1.0f64..1.0, uz in -1.0f64..1.0,
            s in -2.0f64..2.0, h in 0.0f64..0.5,
        ) {
            let a = Vector3::new(ax, ay, az);
            let u = Vector3::new(ux, uy, uz);
            prop_assume!(u.norm() > 1e-3);
            let normal = u.cross(&Vector3::new(uz, ux, uy + 1.0));
            prop_assume!(normal.norm() > 1e-3);
            let b = a + u;
            let c = b + u * s + normal.normalize() * h;
            prop_assert!((line_error(&a, &b, &c) - h).abs() < 1e-9);
        }
    }
}
