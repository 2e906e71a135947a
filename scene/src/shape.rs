//! Object shapes: primitives, and convex objects given as a mesh file.

use crate::error::ShapeError;
use akl_mesh::ConvexHull;
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A shape in its object's frame, centred on the frame origin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// A capsule: a cylinder of `length` along the frame's z axis with a hemisphere of its
    /// radius on each end (as in URDF; `length` excludes the ends).
    Capsule {
        /// Radius (metres).
        radius: f64,
        /// Length of the cylindrical part along z (metres).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (metres).
        radius: f64,
    },
    /// A convex object given as a mesh file (STL, OBJ or COLLADA, in metres): the convex hull
    /// of its vertices, centred on the middle of its bounding box (the object's pose places
    /// that middle), with its own volume and centre of mass.
    Mesh {
        /// The file, relative to the task file's folder (or absolute).
        file: String,
        /// Its convex hull; read when the task file is loaded ([`Shape::resolve`]).
        #[serde(skip)]
        hull: Option<Arc<ConvexHull>>,
    },
}

impl Shape {
    /// Half extents of the shape's bounding box in its own frame.
    pub fn half_extents(&self) -> Vector3<f64> {
        match *self {
            Shape::Box { size } => Vector3::new(size[0], size[1], size[2]) * 0.5,
            Shape::Cylinder { radius, length } => Vector3::new(radius, radius, 0.5 * length),
            Shape::Capsule { radius, length } => {
                Vector3::new(radius, radius, 0.5 * length + radius)
            }
            Shape::Sphere { radius } => Vector3::repeat(radius),
            Shape::Mesh { ref hull, .. } => {
                hull.as_ref().map_or(Vector3::zeros(), |h| h.half_extents)
            }
        }
    }

    /// The convex hull of a mesh shape (`None` for the primitives, and for a mesh not yet
    /// read).
    pub fn hull(&self) -> Option<&ConvexHull> {
        match self {
            Shape::Mesh { hull, .. } => hull.as_deref(),
            _ => None,
        }
    }

    /// Reads a mesh shape's file, relative to `folder` (the task file's), and keeps its hull;
    /// nothing for the primitives. Errors name the file.
    pub fn resolve(&mut self, folder: &std::path::Path) -> Result<(), akl_mesh::MeshError> {
        if let Shape::Mesh { file, hull } = self {
            let path = folder.join(file.as_str());
            *hull = Some(Arc::new(ConvexHull::from_file(&path)?));
        }
        Ok(())
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
            Shape::Capsule { radius, length } => {
                Vector3::from_fn(|i, _| 0.5 * length * m[(i, 2)].abs() + radius)
            }
            Shape::Sphere { radius } => Vector3::repeat(radius),
            Shape::Mesh { ref hull, .. } => {
                let rotation = pose.rotation;
                hull.as_ref().map_or(Vector3::zeros(), |h| {
                    h.vertices
                        .iter()
                        .fold(Vector3::zeros(), |m, v| m.sup(&(rotation * v.coords).abs()))
                })
            }
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
            Shape::Capsule { radius, length } => {
                std::f64::consts::PI * radius * radius * (length + 4.0 / 3.0 * radius)
            }
            Shape::Sphere { radius } => 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
            Shape::Mesh { ref hull, .. } => hull.as_ref().map_or(0.0, |h| h.volume),
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
            Shape::Cylinder { radius, .. }
            | Shape::Capsule { radius, .. }
            | Shape::Sphere { radius } => x.hypot(y) - radius,
            Shape::Mesh { ref hull, .. } => hull
                .as_ref()
                .map_or(x.hypot(y), |h| polygon_excess(&h.outline, x, y)),
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
    pub fn validate(&self) -> Result<(), ShapeError> {
        let values: Vec<(&'static str, f64)> = match *self {
            Shape::Box { size } => vec![
                ("size x", size[0]),
                ("size y", size[1]),
                ("size z", size[2]),
            ],
            Shape::Cylinder { radius, length } => vec![("radius", radius), ("length", length)],
            Shape::Capsule { radius, length } => {
                if !length.is_finite() || length < 0.0 {
                    return Err(ShapeError::NegativeLength(length));
                }
                vec![("radius", radius)]
            }
            Shape::Sphere { radius } => vec![("radius", radius)],
            Shape::Mesh { ref file, ref hull } => {
                if hull.is_none() {
                    return Err(ShapeError::MeshNotRead(file.clone()));
                }
                Vec::new()
            }
        };
        for (what, value) in values {
            if !value.is_finite() || value <= 0.0 {
                return Err(ShapeError::NotPositive { what, value });
            }
        }
        Ok(())
    }

    /// A short human description, e.g. `box 0.05×0.05×0.08`.
    pub fn describe(&self) -> String {
        match *self {
            Shape::Box { size } => format!("box {}×{}×{}", size[0], size[1], size[2]),
            Shape::Cylinder { radius, length } => format!("cylinder r {radius} × {length}"),
            Shape::Capsule { radius, length } => format!("capsule r {radius} × {length}"),
            Shape::Sphere { radius } => format!("sphere r {radius}"),
            Shape::Mesh { ref file, ref hull } => {
                let h = self.half_extents() * 2.0;
                match hull {
                    Some(_) => format!("mesh {file} ({:.3}×{:.3}×{:.3})", h.x, h.y, h.z),
                    None => format!("mesh {file}"),
                }
            }
        }
    }
}

/// How far the point (x, y) lies outside the convex, counter-clockwise `polygon`: the largest
/// signed distance to its edges' lines (negative inside), as a box's excess is the larger of
/// its axes'.
fn polygon_excess(polygon: &[[f64; 2]], x: f64, y: f64) -> f64 {
    (0..polygon.len())
        .map(|i| {
            let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let length = ex.hypot(ey).max(f64::MIN_POSITIVE);
            // Outward normal of a counter-clockwise edge: (ey, -ex).
            ((x - a[0]) * ey - (y - a[1]) * ex) / length
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz_rpy;
    use std::f64::consts::{FRAC_PI_2, PI};

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
    fn a_capsule_reaches_its_radius_beyond_its_length() {
        let c = Shape::Capsule {
            radius: 0.02,
            length: 0.1,
        };
        assert!((c.half_extents() - Vector3::new(0.02, 0.02, 0.07)).norm() < 1e-12);
        let lying = pose_from_xyz_rpy([0.0, 0.0, 0.02], [0.0, FRAC_PI_2, 0.0]);
        let h = c.world_half_extents(&lying);
        assert!(
            (h.z - 0.02).abs() < 1e-12 && (h.x - 0.07).abs() < 1e-12,
            "{h}"
        );
        let v = PI * 0.02f64.powi(2) * 0.1 + 4.0 / 3.0 * PI * 0.02f64.powi(3);
        assert!((c.volume() - v).abs() < 1e-15);
        assert!(Shape::Capsule {
            radius: 0.02,
            length: -1.0
        }
        .validate()
        .is_err());
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

    /// A hexagonal prism (circumradius `r`, height `h`) as a mesh shape, its points lifted
    /// off their origin as a file's may be.
    fn hexagonal_prism(r: f64, h: f64) -> Shape {
        let points: Vec<Point3<f64>> = (0..6)
            .flat_map(|k| {
                let a = f64::from(k) * std::f64::consts::FRAC_PI_3;
                [0.0, h].map(|z| Point3::new(r * a.cos(), r * a.sin(), z + 0.3))
            })
            .collect();
        let hull = ConvexHull::of(&points, std::path::Path::new("hex.stl")).unwrap();
        Shape::Mesh {
            file: "hex.stl".into(),
            hull: Some(Arc::new(hull)),
        }
    }

    #[test]
    fn a_mesh_is_its_centred_hull() {
        let (r, h) = (0.03, 0.07);
        let hex = hexagonal_prism(r, h);
        let apothem = r * 3f64.sqrt() / 2.0;
        assert!((hex.half_extents() - Vector3::new(r, apothem, h / 2.0)).norm() < 1e-6);
        let area = 1.5 * 3f64.sqrt() * r * r;
        assert!((hex.volume() - area * h).abs() < 1e-7, "{}", hex.volume());
        // Seen from above: inside by the apothem at the centre; beyond a corner by the
        // distance to its edges' lines (as a box's excess is the larger axis one).
        assert!((hex.outline_excess(0.0, 0.0) + apothem).abs() < 1e-6);
        assert!((hex.outline_excess(r + 0.01, 0.0) - 0.01 * (PI / 6.0).cos()).abs() < 1e-6);
        assert!(hex.outline_excess(0.0, apothem - 0.001) < 0.0);
        // Standing, its lowest point is half its height below its pose; turned on its side,
        // its circumradius.
        let on_side = pose_from_xyz_rpy([0.0, 0.0, 0.0], [FRAC_PI_2, 0.0, 0.0]);
        assert!((hex.world_half_extents(&on_side).z - apothem).abs() < 1e-6);
        assert!(hex.validate().is_ok());
        assert!(hex.describe().contains("hex.stl"));
    }

    #[test]
    fn an_unread_mesh_is_refused_and_a_missing_file_named() {
        let mut unread = Shape::Mesh {
            file: "part.stl".into(),
            hull: None,
        };
        let e = unread.validate().unwrap_err().to_string();
        assert!(
            e.contains("part.stl") && e.contains("loaded from its file"),
            "{e}"
        );
        let e = unread
            .resolve(std::path::Path::new("no/such/folder"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no/such/folder/part.stl"), "{e}");
    }

    #[test]
    fn validation_rejects_non_positive_sizes() {
        assert!(Shape::Sphere { radius: 0.0 }.validate().is_err());
        assert!(Shape::Box {
            size: [0.1, f64::NAN, 0.1]
        }
        .validate()
        .unwrap_err()
        .to_string()
        .contains("size y"));
    }
}
