//! Spheres that hold a collision element, and closed-form distances from a point to the
//! world's objects: cheap lower bounds on how far an element is from an object or from
//! another element, so that the exact (GJK) queries are asked only where the bound cannot
//! settle the question.
//!
//! An element is a convex polytope (a link's hull, a box, a capsule's segment, ...) grown by
//! a border. It is cut into slabs across its longest extent; each slab of a convex polytope is
//! the convex hull of the polytope's vertices within it and of the points where the
//! polytope's edges cross the slab's two planes. Every chord between two vertices lies in the
//! polytope, so crossing every chord (a superset of the edges) finds those points; the ball
//! about them holds their hull, which is the slab, since a ball is convex. The union of the
//! slabs' balls, each grown by the border, therefore holds the grown element, and the
//! distance from any ball (less its radius) bounds the element's distance from below.

use crate::geometry::{box_corners, Geometry};
use crate::parry_convert::{widest_face, Slab};
use akl_scene::Shape;
use akl_tsr::nalgebra::{Matrix3, Vector3};
use akl_tsr::Pose;
use smallvec::SmallVec;

/// Rounding allowance added to every ball's radius (metres): the balls are computed in f64,
/// the exact shapes parry tests in f32 stand off the meshes by at least a micrometre more.
const ROUNDING: f64 = 1e-9;

/// Most slabs an element is cut into.
pub(super) const MAX_SLABS: usize = 8;

/// Balls whose union holds a collision element (in the element's parry frame): one per slab,
/// the element's border included.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Spheres {
    pub(super) centres: Vec<Vector3<f64>>,
    pub(super) radii: Vec<f64>,
}

impl Spheres {
    /// The balls holding `geometry` (in the frame of its parry shape, see
    /// [`crate::parry_convert::robot_shape`]), cut into slabs no thicker than `slab` metres.
    pub(super) fn of_geometry(geometry: &Geometry, slab: f64) -> Spheres {
        let (vertices, border) = polytope(geometry);
        cover(&vertices, border, slab)
    }

    /// The same balls with every radius grown by `by`.
    pub(super) fn grown(&self, by: f64) -> Spheres {
        Spheres {
            centres: self.centres.clone(),
            radii: self.radii.iter().map(|r| r + by).collect(),
        }
    }
}

/// The vertices of a convex polytope, grown by the returned border, that holds `geometry` in
/// the frame of its parry shape.
fn polytope(geometry: &Geometry) -> (Vec<Vector3<f64>>, f64) {
    let corners = |h: [f64; 3]| box_corners(Vector3::from(h)).to_vec();
    match *geometry {
        Geometry::RoundHull(ref hull) => (
            hull.vertices.iter().map(|v| v.coords).collect(),
            hull.border,
        ),
        Geometry::Capsule { radius, length } => (
            vec![
                Vector3::new(0.0, 0.0, -0.5 * length),
                Vector3::new(0.0, 0.0, 0.5 * length),
            ],
            radius,
        ),
        Geometry::Box { size } => (corners(size.map(|s| 0.5 * s)), 0.0),
        // parry's cylinder runs along y: the box around it.
        Geometry::Cylinder { radius, length } => (corners([radius, 0.5 * length, radius]), 0.0),
        Geometry::Sphere { radius } => (vec![Vector3::zeros()], radius),
    }
}

/// Balls whose union holds the convex hull of `points` grown by `border`: the hull is cut
/// across the longest extent of the points into slabs no thicker than `slab` (at most
/// [`MAX_SLABS`]), each held by one ball (see the module documentation).
pub(super) fn cover(points: &[Vector3<f64>], border: f64, slab: f64) -> Spheres {
    let mut spheres = Spheres::default();
    let Some(first) = points.first() else {
        return spheres;
    };
    let (lo, hi) = points
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let axis = (hi - lo).imax();
    let (from, to) = (lo[axis], hi[axis]);
    let count = (((to - from) / slab).ceil() as usize).clamp(1, MAX_SLABS);
    let plane = |k: usize| {
        if k == count {
            to
        } else {
            from + (to - from) * k as f64 / count as f64
        }
    };
    for k in 0..count {
        let (a, b) = (plane(k), plane(k + 1));
        // The slab's vertices: the points within it, and where chords cross its planes.
        let mut piece: Vec<Vector3<f64>> = points
            .iter()
            .filter(|p| p[axis] >= a && p[axis] <= b)
            .copied()
            .collect();
        for (i, p) in points.iter().enumerate() {
            for q in &points[i + 1..] {
                for cut in [a, b] {
                    let (u, v) = (p[axis] - cut, q[axis] - cut);
                    if (u < 0.0 && v > 0.0) || (u > 0.0 && v < 0.0) {
                        let mut x = p + (q - p) * (u / (u - v));
                        x[axis] = cut;
                        piece.push(x);
                    }
                }
            }
        }
        let Some(first) = piece.first() else {
            continue;
        };
        let (plo, phi) = piece
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let centre = 0.5 * (plo + phi);
        let reach = piece
            .iter()
            .map(|p| (p - centre).norm())
            .fold(0.0, f64::max);
        spheres.centres.push(centre);
        spheres.radii.push(reach + border + ROUNDING);
    }
    spheres
}

/// An object of the world in its own frame, for closed-form distances from points.
#[derive(Debug, Clone)]
pub(super) enum Solid {
    /// A box with these half extents.
    Box(Vector3<f64>),
    /// A cylinder along z.
    Cylinder { radius: f64, half_length: f64 },
    /// A capsule along z.
    Capsule { radius: f64, half_length: f64 },
    /// A ball.
    Ball(f64),
    /// Anything else: only its world-axis-aligned box is used.
    Other,
}

impl Solid {
    /// The solid of a scene shape.
    pub(super) fn of(shape: &Shape) -> Solid {
        match *shape {
            Shape::Box { size } => Solid::Box(Vector3::from(size.map(|s| 0.5 * s))),
            Shape::Cylinder { radius, length } => Solid::Cylinder {
                radius,
                half_length: 0.5 * length,
            },
            Shape::Capsule { radius, length } => Solid::Capsule {
                radius,
                half_length: 0.5 * length,
            },
            Shape::Sphere { radius } => Solid::Ball(radius),
            Shape::Mesh { .. } => Solid::Other,
        }
    }
}

/// A world object as the bounds see it: its solid, the inverse of its pose and its
/// world-axis-aligned box.
#[derive(Debug, Clone)]
pub(super) struct Target {
    pub(super) solid: Solid,
    /// World to the object's frame.
    pub(super) inverse: Placement,
    pub(super) min: Vector3<f64>,
    pub(super) max: Vector3<f64>,
}

impl Target {
    /// The object `shape` placed at `pose`, with its world-axis-aligned box.
    pub(super) fn of(shape: &Shape, pose: &Pose) -> Target {
        let h = shape.world_half_extents(pose);
        let c = pose.translation.vector;
        Target {
            solid: Solid::of(shape),
            inverse: Placement::of(&pose.inverse()),
            min: c - h,
            max: c + h,
        }
    }

    /// Distance from the world point `p` to the object (0 inside): exact for the primitives,
    /// the distance to its box for anything else (never more than the exact one).
    #[inline]
    pub(super) fn distance(&self, p: &Vector3<f64>) -> f64 {
        let local = |p: &Vector3<f64>| self.inverse.apply(p);
        match self.solid {
            Solid::Box(h) => {
                let l = local(p);
                l.abs().zip_map(&h, |x, h| (x - h).max(0.0)).norm()
            }
            Solid::Cylinder {
                radius,
                half_length,
            } => {
                let l = local(p);
                let radial = (l.x.hypot(l.y) - radius).max(0.0);
                let axial = (l.z.abs() - half_length).max(0.0);
                radial.hypot(axial)
            }
            Solid::Capsule {
                radius,
                half_length,
            } => {
                let l = local(p);
                let z = l.z.clamp(-half_length, half_length);
                (Vector3::new(l.x, l.y, l.z - z).norm() - radius).max(0.0)
            }
            Solid::Ball(radius) => (local(p).norm() - radius).max(0.0),
            Solid::Other => (self.min - p)
                .sup(&(p - self.max))
                .sup(&Vector3::zeros())
                .norm(),
        }
    }

    /// A lower bound on the distance between the object and the balls of `spheres` placed
    /// by `place` (element frame to world): negative or 0 when a ball reaches it.
    #[inline]
    pub(super) fn gap(&self, spheres: &Spheres, place: &Placement) -> f64 {
        spheres
            .centres
            .iter()
            .zip(&spheres.radii)
            .map(|(c, r)| self.distance(&place.apply(c)) - r)
            .fold(f64::INFINITY, f64::min)
    }

    /// For a box, the widest slab between the balls of `spheres` placed by `place` and the
    /// box across one of the box's faces (its normal from the box towards the balls); `None`
    /// for other objects. A gap across a face can be closed only by motion along its normal,
    /// which is often much less than the motion itself (an arm sliding along a shelf), so a
    /// proof may bound that motion alone.
    #[inline]
    pub(super) fn face(&self, spheres: &Spheres, place: &Placement) -> Option<Slab> {
        let Solid::Box(h) = self.solid else {
            return None;
        };
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for (c, r) in spheres.centres.iter().zip(&spheres.radii) {
            let l = self.inverse.apply(&place.apply(c));
            lo = lo.inf(&l.add_scalar(-r));
            hi = hi.sup(&l.add_scalar(*r));
        }
        let (axis, sign, width) = widest_face(lo - h, -h - hi);
        Some(Slab {
            normal: sign * self.inverse.rotation.row(axis).transpose(),
            width,
        })
    }

    /// Whether a ball of `inside` placed by `place` reaches into the object: with balls
    /// inside an element ([`super::inside`]), a certain collision. Only the primitives'
    /// distances are exact; for anything else, `false`.
    #[inline]
    pub(super) fn reaches(&self, inside: &Spheres, place: &Placement) -> bool {
        !matches!(self.solid, Solid::Other)
            && inside
                .centres
                .iter()
                .zip(&inside.radii)
                .any(|(c, r)| self.distance(&place.apply(c)) < *r)
    }
}

/// A rigid placement as a rotation matrix and a translation, for placing many points.
#[derive(Debug, Clone, Copy)]
pub(super) struct Placement {
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
}

impl Placement {
    /// The placement of `pose`.
    pub(super) fn of(pose: &Pose) -> Placement {
        Placement {
            rotation: *pose.rotation.to_rotation_matrix().matrix(),
            translation: pose.translation.vector,
        }
    }

    /// Where `p` goes.
    #[inline(always)]
    pub(super) fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }
}

/// A lower bound on the distance between two elements from their balls, `a`'s placed by
/// `pa` and `b`'s by `pb` (negative when balls overlap).
pub(super) fn gap_between(a: &Spheres, pa: &Placement, b: &Spheres, pb: &Placement) -> f64 {
    let placed: SmallVec<[Vector3<f64>; MAX_SLABS]> =
        b.centres.iter().map(|c| pb.apply(c)).collect();
    let mut best = f64::INFINITY;
    for (c, r) in a.centres.iter().zip(&a.radii) {
        let c = pa.apply(c);
        for (d, s) in placed.iter().zip(&b.radii) {
            best = best.min((c - d).norm() - r - s);
        }
    }
    best
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::collision::model::collision_elements;
    use crate::parry_convert;
    use crate::robot::Robot;
    use akl_tsr::nalgebra::{Point3, Translation3, UnitQuaternion};
    use proptest::prelude::*;
    use std::sync::OnceLock;

    /// What parry's single-precision queries are trusted to (metres).
    const PARRY: f64 = 1e-4;

    /// The Panda's collision elements with their balls (at the planner's slab size).
    fn panda() -> &'static Vec<(Geometry, Spheres)> {
        static ELEMENTS: OnceLock<Vec<(Geometry, Spheres)>> = OnceLock::new();
        ELEMENTS.get_or_init(|| {
            let robot = Robot::panda().unwrap();
            collision_elements(&robot)
                .into_iter()
                .map(|(_, g, _)| {
                    let s = Spheres::of_geometry(&g, 0.12);
                    (g, s)
                })
                .collect()
        })
    }

    /// How far `p` lies outside the union of the balls less `border` (negative inside).
    fn outside(spheres: &Spheres, border: f64, p: &Vector3<f64>) -> f64 {
        spheres
            .centres
            .iter()
            .zip(&spheres.radii)
            .map(|(c, r)| (p - c).norm() - (r - border))
            .fold(f64::INFINITY, f64::min)
    }

    /// Any pose within `reach` of the origin (per axis), turned any way.
    pub(in crate::collision) fn arb_pose(reach: f64) -> impl Strategy<Value = Pose> {
        (
            prop::array::uniform3(-reach..reach),
            prop::array::uniform3(-3.2..3.2f64),
        )
            .prop_map(|(t, r)| {
                Pose::from_parts(
                    Translation3::new(t[0], t[1], t[2]),
                    UnitQuaternion::from_euler_angles(r[0], r[1], r[2]),
                )
            })
    }

    /// A box, cylinder, capsule or ball of 1–50 cm.
    pub(in crate::collision) fn arb_shape() -> impl Strategy<Value = Shape> {
        let len = 0.01..0.5f64;
        prop_oneof![
            prop::array::uniform3(len.clone()).prop_map(|size| Shape::Box { size }),
            (len.clone(), len.clone()).prop_map(|(radius, length)| Shape::Cylinder {
                radius: 0.5 * radius,
                length
            }),
            (len.clone(), len.clone()).prop_map(|(radius, length)| Shape::Capsule {
                radius: 0.5 * radius,
                length
            }),
            len.prop_map(|radius| Shape::Sphere { radius }),
        ]
    }

    #[test]
    fn every_hull_vertex_of_the_panda_lies_in_a_ball() {
        for (geometry, spheres) in panda() {
            let (vertices, border) = polytope(geometry);
            assert!(!spheres.centres.is_empty() && spheres.centres.len() <= MAX_SLABS);
            for v in &vertices {
                assert!(outside(spheres, border, v) <= 0.0, "{geometry:?}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Every point of every Panda element's hull (a convex combination of its vertices)
        /// lies in a ball less the border.
        #[test]
        fn the_balls_hold_every_point_of_the_panda_hulls(
            element in 0usize..64,
            weights in prop::collection::vec(0.0..1.0f64, 4),
            picks in prop::collection::vec(0usize..1000, 4),
        ) {
            let (geometry, spheres) = &panda()[element % panda().len()];
            let (vertices, border) = polytope(geometry);
            let total: f64 = weights.iter().sum::<f64>().max(1e-12);
            let p = picks
                .iter()
                .zip(&weights)
                .map(|(i, w)| vertices[i % vertices.len()] * (w / total))
                .sum::<Vector3<f64>>();
            prop_assert!(outside(spheres, border, &p) <= 1e-12);
        }

        /// The same for the hull of any point cloud, cut into any slabs.
        #[test]
        fn the_balls_hold_every_point_of_any_hull(
            points in prop::collection::vec(prop::array::uniform3(-0.3..0.3f64), 1..24),
            weights in prop::collection::vec(0.0..1.0f64, 24),
            slab in 0.005..0.5f64,
        ) {
            let points: Vec<Vector3<f64>> = points.into_iter().map(Vector3::from).collect();
            let spheres = cover(&points, 0.0, slab);
            let total: f64 = weights.iter().take(points.len()).sum::<f64>().max(1e-12);
            let p = points.iter().zip(&weights).map(|(v, w)| v * (w / total)).sum::<Vector3<f64>>();
            prop_assert!(outside(&spheres, 0.0, &p) <= 1e-12);
            for v in &points {
                prop_assert!(outside(&spheres, 0.0, v) <= 1e-12);
            }
        }

        /// The closed-form distance from a point to an object is parry's.
        #[test]
        fn point_distances_are_exact(
            shape in arb_shape(),
            pose in arb_pose(0.5),
            p in prop::array::uniform3(-1.0..1.0f64),
        ) {
            let target = Target::of(&shape, &pose);
            let p = Vector3::from(p);
            let (parry, fix) = parry_convert::object_shape(&shape, 0.0);
            let local = (pose * fix).inverse() * Point3::from(p);
            let local = parry3d_f64::math::Vector::new(local.x, local.y, local.z);
            let exact = parry.as_ref().distance_to_local_point(local, true);
            prop_assert!((target.distance(&p) - exact).abs() <= PARRY, "{} {}", target.distance(&p), exact);
        }

        /// The balls' bound on a Panda element's distance to an object never exceeds the
        /// exact distance (parry's, and the distance to the nearest hull vertex).
        #[test]
        fn the_bound_never_exceeds_the_distance_to_an_object(
            element in 0usize..64,
            shape in arb_shape(),
            pose in arb_pose(0.4),
            at in arb_pose(0.1),
            margin in 0.0..0.02f64,
        ) {
            let (geometry, spheres) = &panda()[element % panda().len()];
            let target = Target::of(&shape, &pose);
            let bound = target.gap(&spheres.grown(margin), &Placement::of(&at));
            let (element_shape, _) = parry_convert::robot_shape(geometry, margin);
            let (object, fix) = parry_convert::object_shape(&shape, 0.0);
            let exact = parry_convert::distance(&element_shape, &at, &object, &(pose * fix)).unwrap();
            prop_assert!(bound <= exact + PARRY, "bound {bound} exact {exact}");
            let (vertices, border) = polytope(geometry);
            let nearest = vertices
                .iter()
                .map(|v| target.distance(&(at * Point3::from(*v)).coords))
                .fold(f64::INFINITY, f64::min);
            prop_assert!(bound <= nearest - border - margin + 1e-9);
        }

        /// The slab across a box's face separates a Panda element (its hull grown by its
        /// border and a margin) from the box by at least its width along its normal: the
        /// hull's extent along the normal and the box's corners' lie that far apart.
        #[test]
        fn a_face_slab_separates_the_element_from_the_box_by_its_width(
            element in 0usize..64,
            size in prop::array::uniform3(0.01..0.5f64),
            pose in arb_pose(0.4),
            at in arb_pose(0.1),
            margin in 0.0..0.02f64,
        ) {
            let (geometry, spheres) = &panda()[element % panda().len()];
            let target = Target::of(&Shape::Box { size }, &pose);
            let slab = target.face(&spheres.grown(margin), &Placement::of(&at)).unwrap();
            prop_assert!((slab.normal.norm() - 1.0).abs() < 1e-12);
            let (vertices, border) = polytope(geometry);
            let grown = border + margin;
            let along = |p: Vector3<f64>| p.dot(&slab.normal);
            let element: Vec<f64> = vertices.iter().map(|v| along((at * Point3::from(*v)).coords)).collect();
            let low = element.iter().copied().fold(f64::INFINITY, f64::min) - grown;
            let box_high = box_corners(Vector3::from(size.map(|s| 0.5 * s)))
                .iter()
                .map(|c| along((pose * Point3::from(*c)).coords))
                .fold(f64::NEG_INFINITY, f64::max);
            // The normal points from the box towards the balls.
            let apart = low - box_high;
            prop_assert!(slab.width <= apart + 1e-9, "width {} apart {}", slab.width, apart);
        }

        /// The same between two elements.
        #[test]
        fn the_bound_never_exceeds_the_distance_between_elements(
            a in 0usize..64,
            b in 0usize..64,
            pa in arb_pose(0.2),
            pb in arb_pose(0.2),
            margin in 0.0..0.01f64,
        ) {
            let (ga, sa) = &panda()[a % panda().len()];
            let (gb, sb) = &panda()[b % panda().len()];
            let bound = gap_between(
                &sa.grown(margin),
                &Placement::of(&pa),
                &sb.grown(margin),
                &Placement::of(&pb),
            );
            let (shape_a, _) = parry_convert::robot_shape(ga, margin);
            let (shape_b, _) = parry_convert::robot_shape(gb, margin);
            let exact = parry_convert::distance(&shape_a, &pa, &shape_b, &pb).unwrap();
            prop_assert!(bound <= exact + PARRY, "bound {bound} exact {exact}");
        }
    }
}
