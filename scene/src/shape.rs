//! Primitive object shapes.

use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};

/// A primitive shape in its object's frame, centred on the frame origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A box with full side lengths along the frame's x, y and z axes (metres).
    Box {
        /// Side lengths [x, y, z].
        size: [f64; 3],
    },
    /// A cylinder whose axis is the frame's z axis (as in URDF; note parry and rapier use y).
    Cylinder {
        /// Radius (metres).
        radius: f64,
        /// Length along z (metres).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (metres).
        radius: f64,
    },
}

impl Shape {
    /// Half extents of the shape's bounding box in its own frame.
    pub fn half_extents(&self) -> Vector3<f64> {
        match *self {
            Shape::Box { size } => Vector3::new(size[0], size[1], size[2]) * 0.5,
            Shape::Cylinder { radius, length } => Vector3::new(radius, radius, 0.5 * length),
            Shape::Sphere { radius } => Vector3::repeat(radius),
        }
    }

    /// Half extents of the tightest world-axis-aligned box around the shape at `pose`.
    pub fn world_half_extents(&self, pose: &Pose) -> Vector3<f64> {
        let r = pose.rotation.to_rotation_matrix();
        let m = r.matrix();
        match *self {
            Shape::Box { .. } => m.abs() * self.half_extents(),
            Shape::Cylinder { radius, length } => Vector3::from_fn(|i, _| {
                let axis = m[(i, 2)].abs();
                0.5 * length * axis + radius * (1.0 - axis * axis).max(0.0).sqrt()
            }),
            Shape::Sphere { radius } => Vector3::repeat(radius),
        }
    }

    /// Lowest world z of the shape at `pose`.
    pub fn bottom(&self, pose: &Pose) -> f64 {
        pose.translation.z - self.world_half_extents(pose).z
    }

    /// Highest world z of the shape at `pose`.
    pub fn top(&self, pose: &Pose) -> f64 {
        pose.translation.z + self.world_half_extents(pose).z
    }

    /// Volume in cubic metres.
    pub fn volume(&self) -> f64 {
        match *self {
            Shape::Box { size } => size[0] * size[1] * size[2],
            Shape::Cylinder { radius, length } => std::f64::consts::PI * radius * radius * length,
            Shape::Sphere { radius } => 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
        }
    }

    /// Whether the point (in the shape's frame, projected on its x-y plane) lies within the
    /// shape's outline seen from above, shrunk by `margin`.
    pub fn outline_contains(&self, x: f64, y: f64, margin: f64) -> bool {
        self.outline_excess(x, y) <= -margin
    }

    /// How far (metres) the point (in the shape's frame, projected on its x-y plane) lies
    /// outside the shape's outline seen from above; negative inside. For a box it is the
    /// larger of the two axis excesses, so a box shrunk or grown by `d` on every side has its
    /// edge where the excess is `-d` or `d`.
    pub fn outline_excess(&self, x: f64, y: f64) -> f64 {
        match *self {
            Shape::Box { size } => (x.abs() - 0.5 * size[0]).max(y.abs() - 0.5 * size[1]),
            Shape::Cylinder { radius, .. } | Shape::Sphere { radius } => x.hypot(y) - radius,
        }
    }

    /// The eight corners of the shape's bounding box (in its own frame) placed at `pose`, in
    /// the world frame.
    pub fn corners(&self, pose: &Pose) -> [Point3<f64>; 8] {
        let h = self.half_extents();
        std::array::from_fn(|i| {
            let sign = |bit: usize| if i >> bit & 1 == 1 { 1.0 } else { -1.0 };
            pose * Point3::new(sign(0) * h.x, sign(1) * h.y, sign(2) * h.z)
        })
    }

    /// How far (metres) the shape `other` at `other_pose`, seen from above, reaches beyond
    /// this shape's outline at `pose`: the largest [`Shape::outline_excess`] of the corners of
    /// `other`'s bounding box. Negative when it lies inside with that much to spare.
    pub fn overhang(&self, pose: &Pose, other: &Shape, other_pose: &Pose) -> f64 {
        self.outline_excess_of(pose, &other.corners(other_pose))
    }

    /// The largest [`Shape::outline_excess`] of world `points` for this shape at `pose`.
    pub fn outline_excess_of(&self, pose: &Pose, points: &[Point3<f64>]) -> f64 {
        let to_local = pose.inverse();
        points
            .iter()
            .map(|c| {
                let local = to_local * c;
                self.outline_excess(local.x, local.y)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Checks that every size is finite and positive; the error names the bad value.
    pub fn validate(&self) -> Result<(), String> {
        let values: Vec<(&str, f64)> = match *self {
            Shape::Box { size } => vec![
                ("size x", size[0]),
                ("size y", size[1]),
                ("size z", size[2]),
            ],
            Shape::Cylinder { radius, length } => vec![("radius", radius), ("length", length)],
            Shape::Sphere { radius } => vec![("radius", radius)],
        };
        for (name, v) in values {
            if !v.is_finite() || v <= 0.0 {
                return Err(format!("{name} must be a positive finite length, got {v}"));
            }
        }
        Ok(())
    }

    /// A short human description, e.g. `box 0.05×0.05×0.08`.
    pub fn describe(&self) -> String {
        match *self {
            Shape::Box { size } => format!("box {}×{}×{}", size[0], size[1], size[2]),
            Shape::Cylinder { radius, length } => format!("cylinder r {radius} × {length}"),
            Shape::Sphere { radius } => format!("sphere r {radius}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz_rpy;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn a_cylinder_on_its_side_is_as_tall_as_its_diameter() {
        let c = Shape::Cylinder {
            radius: 0.02,
            length: 0.3,
        };
        let lying = pose_from_xyz_rpy([0.0, 0.0, 0.02], [0.0, FRAC_PI_2, 0.0]);
        let h = c.world_half_extents(&lying);
        assert!((h.z - 0.02).abs() < 1e-12 && (h.x - 0.15).abs() < 1e-12);
        assert!(c.bottom(&lying).abs() < 1e-12);
    }

    #[test]
    fn a_turned_box_grows_its_bounding_box() {
        let b = Shape::Box {
            size: [0.2, 0.1, 0.1],
        };
        let h = b.world_half_extents(&pose_from_xyz_rpy([0.0; 3], [0.0, 0.0, FRAC_PI_2]));
        assert!((h.x - 0.05).abs() < 1e-12 && (h.y - 0.1).abs() < 1e-12);
    }

    #[test]
    fn overhang_measures_how_far_a_footprint_leaves_an_outline() {
        let shelf = Shape::Box {
            size: [0.2, 0.2, 0.1],
        };
        let block = Shape::Box {
            size: [0.05, 0.05, 0.05],
        };
        let at = |x: f64, yaw: f64| pose_from_xyz_rpy([x, 0.0, 0.075], [0.0, 0.0, yaw]);
        let origin = pose_from_xyz_rpy([0.0; 3], [0.0; 3]);
        assert!((shelf.overhang(&origin, &block, &at(0.0, 0.0)) + 0.075).abs() < 1e-12);
        assert!((shelf.overhang(&origin, &block, &at(0.09, 0.0)) - 0.015).abs() < 1e-12);
        // Turned 45 degrees, the corner reaches 0.025 * sqrt(2) from the centre.
        let turned = shelf.overhang(&origin, &block, &at(0.0, std::f64::consts::FRAC_PI_4));
        assert!(
            (turned - (0.025 * 2f64.sqrt() - 0.1)).abs() < 1e-12,
            "{turned}"
        );
        let disc = Shape::Cylinder {
            radius: 0.1,
            length: 0.1,
        };
        assert!(
            (disc.overhang(&origin, &block, &at(0.0, 0.0)) - (0.025 * 2f64.sqrt() - 0.1)).abs()
                < 1e-12
        );
    }

    #[test]
    fn validation_rejects_non_positive_sizes() {
        assert!(Shape::Sphere { radius: 0.0 }.validate().is_err());
        assert!(Shape::Box {
            size: [0.1, f64::NAN, 0.1]
        }
        .validate()
        .unwrap_err()
        .contains("size y"));
    }
}
