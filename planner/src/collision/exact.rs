//! Robot collision elements and scene objects exactly as their geometry gives them, for
//! double-precision queries at poses measured elsewhere: the simulation confirms a deep contact
//! reading with them before it calls the contact a collision.

use crate::geometry::Geometry;
use crate::parry_convert;
use akl_scene::Shape;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// One collision element or scene object, without margins, as the planner's exact queries see
/// it.
#[derive(Clone)]
pub struct ExactShape {
    shape: SharedShape,
    /// The parry shape's pose in the element's or object's frame.
    offset: Pose,
}

impl std::fmt::Debug for ExactShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExactShape")
            .field("shape", &self.shape.shape_type())
            .finish_non_exhaustive()
    }
}

impl ExactShape {
    /// A robot collision element, in its element frame.
    pub fn of_element(geometry: &Geometry) -> ExactShape {
        let (shape, offset) = parry_convert::robot_shape(geometry, 0.0);
        ExactShape { shape, offset }
    }

    /// A scene object, in its object frame.
    pub fn of_object(shape: &Shape) -> ExactShape {
        let (shape, offset) = parry_convert::object_shape(shape, 0.0);
        ExactShape { shape, offset }
    }

    /// A certified lower bound on the distance between this shape at `pose` and `other` at
    /// `other_pose` (metres; 0 when they touch or overlap), `None` if parry has no query for
    /// the pair.
    pub fn distance(&self, pose: &Pose, other: &ExactShape, other_pose: &Pose) -> Option<f64> {
        let (pa, pb) = (pose * self.offset, other_pose * other.offset);
        parry_convert::distance(&self.shape, &pa, &other.shape, &pb)
    }

    /// How deep this shape at `pose` and `other` at `other_pose` interpenetrate (metres): 0
    /// when a separating slab proves them apart, else the penetration depth; `None` if parry
    /// has no query for the pair.
    pub fn penetration(&self, pose: &Pose, other: &ExactShape, other_pose: &Pose) -> Option<f64> {
        if self.distance(pose, other, other_pose)? > 0.0 {
            return Some(0.0);
        }
        let (pa, pb) = (pose * self.offset, other_pose * other.offset);
        parry_convert::penetration(&self.shape, &pa, &other.shape, &pb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz_rpy;

    fn cylinder() -> ExactShape {
        ExactShape::of_object(&Shape::Cylinder {
            radius: 0.035,
            length: 0.2,
        })
    }

    fn plate() -> ExactShape {
        ExactShape::of_element(&Geometry::Box {
            size: [0.02, 0.02, 0.004],
        })
    }

    #[test]
    fn a_plate_pressed_into_a_cylinder_reads_its_depth() {
        // The plate's lower face 1 mm inside the cylinder's side (x = 0.035), face down.
        let plate_pose =
            pose_from_xyz_rpy([0.036, 0.0, 0.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
        let depth = cylinder()
            .penetration(&Pose::identity(), &plate(), &plate_pose)
            .unwrap();
        assert!((depth - 0.001).abs() < 1e-5, "{depth}");
    }

    #[test]
    fn a_plate_beside_a_cylinder_is_its_gap_away() {
        let plate_pose =
            pose_from_xyz_rpy([0.0395, 0.0, 0.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
        let d = cylinder()
            .distance(&Pose::identity(), &plate(), &plate_pose)
            .unwrap();
        assert!((d - 0.0025).abs() < 1e-6, "{d}");
    }

    #[test]
    fn a_plate_beside_a_cylinder_reads_none() {
        let plate_pose =
            pose_from_xyz_rpy([0.0375, 0.0, 0.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
        let depth = cylinder()
            .penetration(&Pose::identity(), &plate(), &plate_pose)
            .unwrap();
        assert_eq!(depth, 0.0);
    }

    #[test]
    fn the_cylinder_runs_along_its_frame_z() {
        // A 4 mm plate centred 1 mm past the end face reaches 1 mm into it along z; the same
        // offset along y (parry's cylinder axis) is far outside the 35 mm radius.
        let above = pose_from_xyz_rpy([0.0, 0.0, 0.101], [0.0, 0.0, 0.0]);
        let beside = pose_from_xyz_rpy([0.0, 0.101, 0.0], [0.0, 0.0, 0.0]);
        let c = cylinder();
        let depth = c.penetration(&Pose::identity(), &plate(), &above).unwrap();
        assert!((depth - 0.001).abs() < 1e-5, "{depth}");
        assert_eq!(
            c.penetration(&Pose::identity(), &plate(), &beside),
            Some(0.0)
        );
    }
}
