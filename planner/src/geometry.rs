//! Collision geometry of robot links, read from the URDF's collision elements.

use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use serde::Serialize;
use std::sync::Arc;

/// A collision shape in its own frame, URDF conventions: capsules and cylinders run along z
/// and are centred on the frame origin.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    /// A convex hull grown by a border: what encloses a link's meshes (`enclosure`).
    RoundHull(#[serde(serialize_with = "hull_summary")] Arc<RoundHull>),
}

/// A grown hull as `robot info --json` shows it: its size, not its vertices.
fn hull_summary<S: serde::Serializer>(hull: &Arc<RoundHull>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut out = s.serialize_struct("RoundHull", 4)?;
    out.serialize_field("vertices", &hull.vertices.len())?;
    out.serialize_field("border", &hull.border)?;
    out.serialize_field("capsule_half_length", &hull.half_length)?;
    out.serialize_field("capsule_radius", &hull.radius)?;
    out.end()
}

/// A convex polytope grown by `border` in every direction (its Minkowski sum with a ball),
/// with the capsule along z that holds it, for culling.
#[derive(Debug, Clone, PartialEq)]
pub struct RoundHull {
    /// The hull's vertices (metres, in the shape's frame).
    pub vertices: Vec<Point3<f64>>,
    /// Its faces, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// How far the shape reaches beyond the hull (metres).
    pub border: f64,
    /// Half the length of the holding capsule's segment, centred on the origin along z.
    pub half_length: f64,
    /// The holding capsule's radius: every point of the grown hull is within it of the
    /// segment.
    pub radius: f64,
}

/// One collision element of a link: a shape and where it sits in the link frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkShape {
    /// The shape.
    pub geometry: Geometry,
    /// Pose of the shape's frame in the link frame.
    #[serde(with = "akl_tsr::pose::serde_pose")]
    pub origin: Pose,
    /// Whether the URDF gives the shape as it is or it encloses the link's meshes.
    pub role: ShapeRole,
}

/// Where a link's collision shape comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeRole {
    /// A URDF primitive (box, capsule, cylinder, sphere), simulated as it is: the fingers'
    /// pads and boxes grasp with these.
    Exact,
    /// A hull grown to hold the link's collision and visual meshes (`enclosure`):
    /// the planner and the simulation's contact verdicts use it so that whatever touches the
    /// real link touches the model.
    Enclosure,
}

impl Geometry {
    /// Converts a k collision geometry: `Some(None)` for a mesh (enclosed by a grown hull
    /// instead, see [`crate::enclosure`]), `None` for a size of zero or less.
    pub(crate) fn from_k(geometry: &k::link::Geometry<f64>) -> Option<Option<Self>> {
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
            k::link::Geometry::Mesh { .. } => return Some(None),
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let valid = match &g {
            Geometry::Capsule { radius, length } => {
                positive(*radius) && length.is_finite() && *length >= 0.0
            }
            Geometry::Box { size } => size.iter().all(|v| positive(*v)),
            Geometry::Cylinder { radius, length } => positive(*radius) && positive(*length),
            Geometry::Sphere { radius } => positive(*radius),
            Geometry::RoundHull(_) => true,
        };
        valid.then_some(Some(g))
    }

    /// Radius of the smallest sphere about the shape's origin that contains it.
    pub(crate) fn bounding_radius(&self) -> f64 {
        match *self {
            Geometry::Capsule { radius, length } => 0.5 * length + radius,
            Geometry::Box { size } => 0.5 * (size[0].hypot(size[1])).hypot(size[2]),
            Geometry::Cylinder { radius, length } => radius.hypot(0.5 * length),
            Geometry::Sphere { radius } => radius,
            Geometry::RoundHull(ref h) => h.half_length + h.radius,
        }
    }
}

/// The eight corners of the box centred on the origin with half extents `half` (along the
/// frame's axes): the vertices bounds and slabs are taken over.
pub(crate) fn box_corners(half: Vector3<f64>) -> [Vector3<f64>; 8] {
    std::array::from_fn(|i| {
        let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
        Vector3::new(s(1) * half.x, s(2) * half.y, s(4) * half.z)
    })
}
