//! Interpenetration tests between objects, on their oriented bounding boxes.

use crate::shape::Shape;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;

/// Depth (metres) two objects may sink into each other before they count as overlapping, so
/// that an object resting on its support (touching, up to rounding) is not an overlap.
pub(crate) const CONTACT_TOLERANCE: f64 = 1e-3;

/// Whether the oriented bounding boxes of two shapes interpenetrate by more than
/// 1 mm, so that an object resting on its support is not an overlap.
///
/// Bounding boxes are exact for boxes and conservative for cylinders and spheres, which is
/// the safe side for placing objects apart.
pub fn shapes_overlap(a: &Shape, pa: &Pose, b: &Shape, pb: &Pose) -> bool {
    penetration(a, pa, b, pb) > CONTACT_TOLERANCE
}

/// How deep (metres) the oriented bounding boxes of two shapes sink into each other: the
/// smallest overlap along the 15 candidate separating axes. Negative when they are apart; its
/// magnitude is then the widest separation along those axes, which never exceeds the true
/// distance between the boxes.
///
/// For boxes the positive value is the exact penetration depth (the separating-axis theorem
/// over face and edge axes).
pub(crate) fn penetration(a: &Shape, pa: &Pose, b: &Shape, pb: &Pose) -> f64 {
    let ra = pa.rotation.to_rotation_matrix();
    let rb = pb.rotation.to_rotation_matrix();
    let (ha, hb) = (a.half_extents(), b.half_extents());
    let axes_a: [Vector3<f64>; 3] = [0, 1, 2].map(|i| ra.matrix().column(i).into_owned());
    let axes_b: [Vector3<f64>; 3] = [0, 1, 2].map(|i| rb.matrix().column(i).into_owned());
    let t = pb.translation.vector - pa.translation.vector;

    let overlap_along = |axis: Vector3<f64>| -> Option<f64> {
        let n = axis.norm();
        if n < 1e-9 {
            return None;
        }
        let l = axis / n;
        let radius = |axes: &[Vector3<f64>; 3], h: &Vector3<f64>| {
            (0..3).map(|i| h[i] * axes[i].dot(&l).abs()).sum::<f64>()
        };
        Some(radius(&axes_a, &ha) + radius(&axes_b, &hb) - t.dot(&l).abs())
    };

    let face_axes = axes_a.iter().chain(axes_b.iter()).copied();
    let edge_axes = axes_a
        .iter()
        .flat_map(|u| axes_b.iter().map(move |v| u.cross(v)));
    face_axes
        .chain(edge_axes)
        .filter_map(overlap_along)
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};

    const CUBE: Shape = Shape::Box {
        size: [0.1, 0.1, 0.1],
    };

    #[test]
    fn stacked_boxes_touch_without_overlapping() {
        assert!(!shapes_overlap(
            &CUBE,
            &pose_from_xyz([0.0; 3]),
            &CUBE,
            &pose_from_xyz([0.0, 0.0, 0.1])
        ));
        assert!(shapes_overlap(
            &CUBE,
            &pose_from_xyz([0.0; 3]),
            &CUBE,
            &pose_from_xyz([0.0, 0.0, 0.09])
        ));
    }

    #[test]
    fn a_turned_box_is_caught_by_its_diagonal() {
        let turned = pose_from_xyz_rpy([0.115, 0.0, 0.0], [0.0, 0.0, std::f64::consts::FRAC_PI_4]);
        // The turned cube reaches 0.0707 towards the other one, whose face is at 0.05.
        assert!(shapes_overlap(
            &CUBE,
            &pose_from_xyz([0.0; 3]),
            &CUBE,
            &turned
        ));
        let farther = pose_from_xyz_rpy([0.125, 0.0, 0.0], [0.0, 0.0, std::f64::consts::FRAC_PI_4]);
        assert!(!shapes_overlap(
            &CUBE,
            &pose_from_xyz([0.0; 3]),
            &CUBE,
            &farther
        ));
    }

    #[test]
    fn penetration_is_the_depth_or_the_gap() {
        let origin = pose_from_xyz([0.0; 3]);
        let d = penetration(&CUBE, &origin, &CUBE, &pose_from_xyz([0.097, 0.0, 0.0]));
        assert!((d - 0.003).abs() < 1e-12, "{d}");
        let d = penetration(&CUBE, &origin, &CUBE, &pose_from_xyz([0.13, 0.02, 0.0]));
        assert!((d + 0.03).abs() < 1e-12, "{d}");
    }

    #[test]
    fn edge_axes_separate_crossed_boxes() {
        let bar = Shape::Box {
            size: [0.4, 0.02, 0.02],
        };
        let a = pose_from_xyz_rpy([0.0; 3], [0.0, 0.0, std::f64::consts::FRAC_PI_4]);
        let b = pose_from_xyz_rpy([0.0, 0.0, 0.03], [0.0, 0.0, -std::f64::consts::FRAC_PI_4]);
        assert!(!shapes_overlap(&bar, &a, &bar, &b));
    }
}
