//! The one place where AKL's nalgebra `f64` poses and shapes become rapier3d's glam `f32`
//! types, and back.

use akl_mesh::ConvexHull;
use akl_planner::cylinder_axis;
use akl_planner::Geometry;
use akl_scene::Shape;
use akl_tsr::nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};
use akl_tsr::Pose;
use rapier3d::prelude::{ColliderBuilder, Pose as SimPose, Rotation, SharedShape, Vector};

/// A pose as rapier's single-precision pose.
pub(crate) fn to_sim(p: &Pose) -> SimPose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion().coords;
    SimPose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.x as f32, q.y as f32, q.z as f32, q.w as f32).normalize(),
    )
}

/// A rapier pose as an AKL pose.
pub(crate) fn from_sim(p: &SimPose) -> Pose {
    let t = p.translation;
    let q = p.rotation;
    Pose::from_parts(
        Translation3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z)),
        UnitQuaternion::from_quaternion(Quaternion::new(
            f64::from(q.w),
            f64::from(q.x),
            f64::from(q.y),
            f64::from(q.z),
        )),
    )
}

/// A rapier vector as an nalgebra vector.
pub(crate) fn vector_from_sim(v: Vector) -> Vector3<f64> {
    Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// The colliders of a scene object, placed at `origin` (the object frame in its body's frame):
/// the one furniture and other objects meet, and, where that one differs from the object's own
/// shape, a second of the own shape alone for the robot to meet.
///
/// A cylinder, capsule or mesh object meets the world as a compound: its own shape, then the
/// rest aids that let it rest as a real object does ([`rest_prism`], [`rest_slabs`]). The aids
/// are for furniture and objects only: the robot meets the own shape instead, because parry's
/// single-precision contacts between two convex polyhedra misread them (a prism was read
/// 6.2 mm deep into a UR5e gripper knuckle 5.1 mm away, which pushed a held bottle out of the
/// hand).
pub(crate) fn object_colliders(
    shape: &Shape,
    origin: &Pose,
) -> (ColliderBuilder, Option<ColliderBuilder>) {
    let (own, at) = own_shape(shape);
    let aids = match *shape {
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
            rest_prism(radius, length).into_iter().collect()
        }
        Shape::Mesh { .. } => rest_slabs(&own),
        Shape::Box { .. } | Shape::Sphere { .. } => Vec::new(),
    };
    let alone = ColliderBuilder::new(own.clone()).position(to_sim(&(origin * at)));
    if aids.is_empty() {
        return (alone, None);
    }
    let parts = std::iter::once((to_sim(&at), own))
        .chain(aids.into_iter().map(|a| (SimPose::IDENTITY, a)))
        .collect();
    let world = ColliderBuilder::new(SharedShape::compound(parts)).position(to_sim(origin));
    (world, Some(alone))
}

/// A collider for a primitive shape alone, placed at `origin`.
fn own_collider(shape: &Shape, origin: &Pose) -> ColliderBuilder {
    let (own, at) = own_shape(shape);
    ColliderBuilder::new(own).position(to_sim(&(origin * at)))
}

/// A scene shape as rapier's shape, and the pose of rapier's shape in the object frame.
fn own_shape(shape: &Shape) -> (SharedShape, Pose) {
    match *shape {
        Shape::Box { size } => (
            SharedShape::cuboid(
                0.5 * size[0] as f32,
                0.5 * size[1] as f32,
                0.5 * size[2] as f32,
            ),
            Pose::identity(),
        ),
        Shape::Cylinder { radius, length } => (
            SharedShape::cylinder(0.5 * length as f32, radius as f32),
            cylinder_axis(),
        ),
        Shape::Capsule { radius, length } => (
            SharedShape::capsule_z(0.5 * length as f32, radius as f32),
            Pose::identity(),
        ),
        Shape::Sphere { radius } => (SharedShape::ball(radius as f32), Pose::identity()),
        Shape::Mesh { ref hull, .. } => (mesh_hull(hull.as_deref()), Pose::identity()),
    }
}

/// A mesh object's hull, as the planner has it (rapier takes its centre of mass and inertia
/// from it).
fn mesh_hull(hull: Option<&ConvexHull>) -> SharedShape {
    let points: Vec<Vector> = hull
        .iter()
        .flat_map(|h| h.vertices.iter())
        .map(|v| Vector::new(v.x as f32, v.y as f32, v.z as f32))
        .collect();
    // A mesh whose hull was measured when the task was loaded always has one; an unread one
    // (refused by task validation) is a point, as the planner takes it.
    SharedShape::convex_hull(&points).unwrap_or_else(|| SharedShape::ball(0.0))
}

/// How deep (metres) the slabs under a mesh object's many-cornered faces reach into it.
const SLAB_DEPTH: f64 = 0.001;

/// The rest slabs of a mesh object's hull: under each face of more than four corners a thin
/// slab inside the hull whose face lies on that face, on four of its corners spread round it.
///
/// parry makes the contact of a face with what it rests on from at most four of the face's
/// corners, and takes the first four in order (`ConvexPolyhedron::local_support_feature` in
/// parry3d 0.31, marked there as a to-do: "select four vertices that maximize the area"), so a
/// hexagonal part stands on four corners along one side of its base and rocks (untouched on a
/// shelf it tilted 0.019 rad and slid 1.8 mm). A slab's face gives four corners round the
/// whole face; the hull keeps the object's shape.
fn rest_slabs(hull: &SharedShape) -> Vec<SharedShape> {
    let Some(polyhedron) = hull.as_convex_polyhedron() else {
        return Vec::new();
    };
    let points = polyhedron.points();
    let ring = polyhedron.vertices_adj_to_face();
    let mut slabs = Vec::new();
    for face in polyhedron.faces() {
        let n = face.num_vertices_or_edges as usize;
        if n <= 4 {
            continue;
        }
        let first = face.first_vertex_or_edge as usize;
        let inward = -face.normal * SLAB_DEPTH as f32;
        let corners: Vec<Vector> = (0..4)
            .map(|k| points[ring[first + k * n / 4] as usize])
            .flat_map(|p| [p, p + inward])
            .collect();
        slabs.extend(SharedShape::convex_hull(&corners));
    }
    slabs
}

/// Sides of the prism that keeps a lying cylinder from rolling.
const PRISM_SIDES: usize = 24;

/// How far (metres) the prism stops short of each end of the cylinder.
const PRISM_INSET: f64 = 0.001;

/// The rest aid of a cylinder or capsule: a [`PRISM_SIDES`]-sided prism along z whose
/// faces touch the cylindrical part (so both rest at the same height), with faces normal to ±x
/// and ±y; `None` when the cylinder is too short to hold it.
///
/// Each alone fails one way. rapier's exact cylinder lying on a box touches it along a line
/// with no rolling resistance, and numerical error sets it rolling (a pipe resting on a rail
/// rolls off within two seconds); the prism rests on a face, as a real pipe held by friction
/// and its own imperfections does. But a prism standing on its end rocks and can fall: parry
/// reduces the contact of its 24-gon end face with a box to four points taken from a few
/// neighbouring corners on one side of the face, a support on one side of the centre of mass
/// (a 2 × 16 cm tube standing untouched tilted 0.08 rad within 2 s, and more sides made it
/// worse; solver iterations and smaller steps did not help), while the exact cylinder's end
/// face gives four points spread round its rim. Together, standing, the cylinder's points
/// carry it; lying, the prism's face does. A capsule touches a flat support along a line as a
/// cylinder does, and gets the same prism over its cylindrical part (standing on a round end,
/// it falls, as it should).
fn rest_prism(radius: f64, length: f64) -> Option<SharedShape> {
    prism(radius, length).filter(|_| length > 2.0 * PRISM_INSET)
}

/// The [`PRISM_SIDES`]-sided prism along z whose faces touch a cylinder of `radius`, stopping
/// [`PRISM_INSET`] short of the ends of a cylinder of `length` (`None` if parry cannot make it).
fn prism(radius: f64, length: f64) -> Option<SharedShape> {
    let n = PRISM_SIDES;
    let corner = radius / (std::f64::consts::PI / n as f64).cos();
    let h = 0.5 * length;
    let prism_h = (h - PRISM_INSET).max(0.5 * h);
    let points: Vec<Vector> = (0..n)
        .flat_map(|k| {
            let a = (2 * k + 1) as f64 * std::f64::consts::PI / n as f64;
            let (x, y) = ((corner * a.cos()) as f32, (corner * a.sin()) as f32);
            [
                Vector::new(x, y, -prism_h as f32),
                Vector::new(x, y, prism_h as f32),
            ]
        })
        .collect();
    SharedShape::convex_hull(&points)
}

/// A collider for one collision element of a robot link, placed at `origin` in the link frame.
pub(crate) fn link_collider(geometry: &Geometry, origin: &Pose) -> ColliderBuilder {
    match *geometry {
        Geometry::Capsule { radius, length } => {
            own_collider(&Shape::Capsule { radius, length }, origin)
        }
        Geometry::Box { size } => own_collider(&Shape::Box { size }, origin),
        Geometry::Cylinder { radius, length } => {
            own_collider(&Shape::Cylinder { radius, length }, origin)
        }
        Geometry::Sphere { radius } => own_collider(&Shape::Sphere { radius }, origin),
        // The hull's own faces; should rapier refuse them, the capsule that holds the hull.
        Geometry::RoundHull(ref hull) => {
            let points: Vec<Vector> = hull
                .vertices
                .iter()
                .map(|v| Vector::new(v.x as f32, v.y as f32, v.z as f32))
                .collect();
            ColliderBuilder::round_convex_mesh(points, &hull.triangles, hull.border as f32)
                .unwrap_or_else(|| {
                    ColliderBuilder::capsule_z(hull.half_length as f32, hull.radius as f32)
                })
                .position(to_sim(origin))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::{pose_from_xyz_rpy, position_distance, rotation_distance};

    #[test]
    fn poses_survive_the_round_trip_to_single_precision() {
        let p = pose_from_xyz_rpy([0.45, -0.32, 0.19], [0.3, -1.2, 2.9]);
        let back = from_sim(&to_sim(&p));
        assert!(position_distance(&p, &back) < 1e-6);
        assert!(rotation_distance(&p, &back) < 1e-6);
    }

    #[test]
    fn a_cylinder_object_lies_along_z_and_touches_the_true_cylinder() {
        let (c, _) = object_colliders(
            &Shape::Cylinder {
                radius: 0.02,
                length: 0.3,
            },
            &Pose::identity(),
        );
        let c = c.build();
        let aabb = c.compute_aabb();
        assert!((aabb.maxs.z - 0.15).abs() < 1e-6, "{aabb:?}");
        assert!((aabb.maxs.y - 0.02).abs() < 1e-6, "{aabb:?}");
    }
}
