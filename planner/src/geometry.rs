//! Collision geometry of robot links, read from the URDF's collision elements.

use akl_tsr::Pose;
use serde::Serialize;

/// A primitive collision shape in its own frame, URDF conventions: capsules and cylinders run
/// along z and are centred on the frame origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Geometry {
    /// A capsule: `length` between the centres of its two end spheres of `radius`.
    Capsule {
        /// Radius (metres).
        radius: f64,
        /// Distance between the end-sphere centres (metres).
        length: f64,
    },
    /// A box with full side lengths along x, y, z.
    Box {
        /// Side lengths (metres).
        size: [f64; 3],
    },
    /// A cylinder of `length` along z.
    Cylinder {
        /// Radius (metres).
        radius: f64,
        /// Length (metres).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (metres).
        radius: f64,
    },
}

/// One collision element of a link: a shape and where it sits in the link frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkShape {
    /// The shape.
    pub geometry: Geometry,
    /// Pose of the shape's frame in the link frame.
    #[serde(with = "akl_tsr::pose::serde_pose")]
    pub origin: Pose,
}

impl Geometry {
    /// Converts a k collision geometry; meshes and non-positive sizes are rejected.
    pub fn from_k(geometry: &k::link::Geometry<f64>) -> Result<Self, String> {
        let g = match geometry {
            k::link::Geometry::Capsule { radius, length } => Geometry::Capsule {
                radius: *radius,
                length: *length,
            },
            k::link::Geometry::Box {
                depth,
                width,
                height,
            } => Geometry::Box {
                size: [*depth, *width, *height],
            },
            k::link::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
                radius: *radius,
                length: *length,
            },
            k::link::Geometry::Sphere { radius } => Geometry::Sphere { radius: *radius },
            k::link::Geometry::Mesh { filename, .. } => {
                return Err(format!(
                    "mesh collision geometry ({filename}) is not supported; use capsules, boxes, cylinders or spheres"
                ))
            }
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let valid = match g {
            Geometry::Capsule { radius, length } => {
                positive(radius) && length.is_finite() && length >= 0.0
            }
            Geometry::Box { size } => size.iter().all(|v| positive(*v)),
            Geometry::Cylinder { radius, length } => positive(radius) && positive(length),
            Geometry::Sphere { radius } => positive(radius),
        };
        if !valid {
            return Err(format!("collision geometry {g:?} has a non-positive size"));
        }
        Ok(g)
    }

    /// Radius of the smallest sphere about the shape's origin that contains it.
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Geometry::Capsule { radius, length } => 0.5 * length + radius,
            Geometry::Box { size } => 0.5 * (size[0].hypot(size[1])).hypot(size[2]),
            Geometry::Cylinder { radius, length } => radius.hypot(0.5 * length),
            Geometry::Sphere { radius } => radius,
        }
    }
}
