//! The one place where nalgebra `f64` poses and shapes become parry3d's glam `f32` types.

use crate::geometry::Geometry;
use akl_scene::Shape;
use akl_tsr::nalgebra::{UnitQuaternion, Vector3};
use akl_tsr::Pose;
use parry3d::math::{Pose as ParryPose, Rotation, Vector};
use parry3d::shape::SharedShape;
use std::f64::consts::FRAC_PI_2;

/// A pose as parry3d's single-precision pose.
pub fn pose(p: &Pose) -> ParryPose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion().coords;
    ParryPose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.x as f32, q.y as f32, q.z as f32, q.w as f32).normalize(),
    )
}

/// URDF and AKL scene cylinders run along z, parry's (and so rapier's) along y: the turn that
/// maps y onto z, applied to the shape before its own pose.
pub fn cylinder_axis() -> Pose {
    Pose::from_parts(
        Vector3::zeros().into(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2),
    )
}

/// A parry shape for a robot collision element grown by `inflate` metres in every direction
/// (an exact Minkowski sum with a ball), and the pose of the parry shape in the element frame.
pub fn robot_shape(geometry: &Geometry, inflate: f64) -> (SharedShape, Pose) {
    let m = inflate as f32;
    match *geometry {
        Geometry::RoundHull(ref hull) => {
            let points: Vec<parry3d::math::Vector> = hull
                .vertices
                .iter()
                .map(|v| parry3d::math::Vector::new(v.x as f32, v.y as f32, v.z as f32))
                .collect();
            let border = (hull.border + inflate) as f32;
            // The hull's own faces (no hull is recomputed); should parry refuse them, the
            // capsule that holds the hull, which holds everything the hull does.
            let shape = SharedShape::round_convex_mesh(points, &hull.triangles, border)
                .unwrap_or_else(|| {
                    SharedShape::capsule_z(hull.half_length as f32, (hull.radius + inflate) as f32)
                });
            (shape, Pose::identity())
        }
        Geometry::Capsule { radius, length } => (
            SharedShape::capsule_z(0.5 * length as f32, radius as f32 + m),
            Pose::identity(),
        ),
        Geometry::Box { size } => (
            SharedShape::round_cuboid(
                0.5 * size[0] as f32,
                0.5 * size[1] as f32,
                0.5 * size[2] as f32,
                m,
            ),
            Pose::identity(),
        ),
        Geometry::Cylinder { radius, length } => (
            SharedShape::round_cylinder(0.5 * length as f32, radius as f32, m),
            cylinder_axis(),
        ),
        Geometry::Sphere { radius } => (SharedShape::ball(radius as f32 + m), Pose::identity()),
    }
}

/// A parry shape for a scene object grown by `inflate` metres, and the pose of the parry shape
/// in the object frame.
pub fn object_shape(shape: &Shape, inflate: f64) -> (SharedShape, Pose) {
    let m = inflate as f32;
    match *shape {
        Shape::Box { size } => {
            let h = [
                0.5 * size[0] as f32,
                0.5 * size[1] as f32,
                0.5 * size[2] as f32,
            ];
            let s = if m > 0.0 {
                SharedShape::round_cuboid(h[0], h[1], h[2], m)
            } else {
                SharedShape::cuboid(h[0], h[1], h[2])
            };
            (s, Pose::identity())
        }
        Shape::Cylinder { radius, length } => {
            let s = if m > 0.0 {
                SharedShape::round_cylinder(0.5 * length as f32, radius as f32, m)
            } else {
                SharedShape::cylinder(0.5 * length as f32, radius as f32)
            };
            (s, cylinder_axis())
        }
        Shape::Capsule { radius, length } => (
            SharedShape::capsule_z(0.5 * length as f32, radius as f32 + m),
            Pose::identity(),
        ),
        Shape::Sphere { radius } => (SharedShape::ball(radius as f32 + m), Pose::identity()),
        Shape::Mesh { ref hull, .. } => {
            let points: Vec<Vector> = hull
                .iter()
                .flat_map(|h| h.vertices.iter())
                .map(|v| Vector::new(v.x as f32, v.y as f32, v.z as f32))
                .collect();
            let made = if m > 0.0 {
                SharedShape::round_convex_hull(&points, m)
            } else {
                SharedShape::convex_hull(&points)
            };
            // A mesh whose hull was measured when the task was loaded always has one; an
            // unread one (refused by task validation) is a point.
            (
                made.unwrap_or_else(|| SharedShape::ball(m)),
                Pose::identity(),
            )
        }
    }
}

/// Whether two parry shapes at the given (f64) poses touch or overlap.
///
/// parry's intersection test alone reports some capsule–cuboid pairs millimetres apart as
/// intersecting (the Panda hand's capsule 2.8 mm from a block, found by the RRT property test
/// with seed 82996, while parry's distance and contact queries agree they are apart), so a
/// positive is confirmed by the distance query. Negatives, the common case, cost nothing more.
pub fn intersects(a: &SharedShape, pa: &Pose, b: &SharedShape, pb: &Pose) -> bool {
    let hit = parry3d::query::intersection_test(&pose(pa), a.as_ref(), &pose(pb), b.as_ref())
        .is_ok_and(|r| r.intersecting);
    hit && distance(a, pa, b, pb).is_none_or(|d| d <= 0.0)
}

/// Distance between two parry shapes at the given (f64) poses, 0 when they touch or overlap;
/// `None` if parry has no distance query for the pair.
pub fn distance(a: &SharedShape, pa: &Pose, b: &SharedShape, pb: &Pose) -> Option<f64> {
    parry3d::query::distance(&pose(pa), a.as_ref(), &pose(pb), b.as_ref())
        .ok()
        .map(|d| f64::from(d.distance).max(0.0))
}

/// How deep two parry shapes at the given (f64) poses interpenetrate (metres; 0 when apart or
/// touching); `None` if parry has no contact query for the pair.
pub fn penetration(a: &SharedShape, pa: &Pose, b: &SharedShape, pb: &Pose) -> Option<f64> {
    parry3d::query::contact(&pose(pa), a.as_ref(), &pose(pb), b.as_ref(), 0.0)
        .ok()
        .map(|c| c.map_or(0.0, |c| f64::from(-c.dist).max(0.0)))
}
