//! Balls that lie inside a collision element: where one of them reaches an object, the
//! element does, so a collision is certain without the exact (GJK) test.
//!
//! Most configurations a search checks on cluttered problems collide, and a plain check
//! pays for the exact test on the pair that collides (BENCHMARKS.md, "Balls inside the
//! links"). The balls [`super::spheres`] puts around an element can only call a pair apart;
//! these can only call it touching, and a pair neither settles goes to parry as before, so
//! every verdict stays the exact test's.
//!
//! A ball is inside a convex polytope when its centre's depth (the least distance to a face
//! plane) is at least its radius, and inside the polytope grown by a border when its radius
//! less the border is at most that depth. An element is cut into slabs across its longest
//! extent; each slab gets the ball whose centre, on the slab's middle plane, lies deepest.

use super::spheres::Spheres;
use crate::geometry::{box_corners, Geometry};
use akl_tsr::nalgebra::Vector3;

/// Thickest slab an element is cut into for its inside balls (metres): two or three balls
/// per arm link. Chosen by measurement (BENCHMARKS.md, "Balls inside the links"): thinner
/// slabs find a few more collisions but cost more in the checks that find none.
const SLAB: f64 = 0.12;

/// Most inside balls an element gets.
const MAX_BALLS: usize = 8;

/// Taken off every inside ball's radius (metres): what parry's intersection test, which
/// decides pairs these balls do not, may round at a touching contact.
const ALLOWANCE: f64 = 1e-6;

/// The deepest-point search stops when its step is below this (metres).
const SEARCH_TOLERANCE: f64 = 1e-5;

/// Balls inside `geometry` (in the frame of its parry shape, see
/// [`crate::parry_convert::robot_shape`]), its border included; grow them by a margin
/// ([`Spheres::grown`]) for balls inside the element grown by that margin.
pub(super) fn inside(geometry: &Geometry) -> Spheres {
    let balls = match *geometry {
        Geometry::RoundHull(ref hull) => {
            let vertices: Vec<Vector3<f64>> = hull.vertices.iter().map(|v| v.coords).collect();
            let planes = hull
                .triangles
                .iter()
                .filter_map(|t| {
                    let [a, b, c] = t.map(|i| vertices[i as usize]);
                    let n = (b - a).cross(&(c - a)).try_normalize(1e-12)?;
                    Some((n, n.dot(&a)))
                })
                .collect::<Vec<_>>();
            deepest_per_slab(&vertices, &planes, hull.border)
        }
        Geometry::Box { size } => {
            let h = Vector3::from(size.map(|s| 0.5 * s));
            let planes: Vec<(Vector3<f64>, f64)> = (0..3)
                .flat_map(|i| {
                    let mut n = Vector3::zeros();
                    n[i] = 1.0;
                    [(n, h[i]), (-n, h[i])]
                })
                .collect();
            deepest_per_slab(&box_corners(h), &planes, 0.0)
        }
        Geometry::Capsule { radius, length } => along_axis(Vector3::z(), 0.5 * length, 0.0, radius),
        // parry's cylinder runs along y: balls on its axis, as wide as it allows.
        Geometry::Cylinder { radius, length } => {
            let r = radius.min(0.5 * length);
            along_axis(Vector3::y(), 0.5 * length, r, r)
        }
        Geometry::Sphere { radius } => vec![(Vector3::zeros(), radius)],
    };
    let (centres, radii) = balls
        .into_iter()
        .map(|(c, r)| (c, r - ALLOWANCE))
        .filter(|(_, r)| *r > 0.0)
        .unzip();
    Spheres { centres, radii }
}

/// Balls of radius `radius` centred on the segment from `-half` to `half` along `axis`, kept
/// `inset` from its ends: the centres a capsule's (inset 0) or a cylinder's balls may take.
fn along_axis(axis: Vector3<f64>, half: f64, inset: f64, radius: f64) -> Vec<(Vector3<f64>, f64)> {
    let reach = (half - inset).max(0.0);
    let count = ((2.0 * reach / SLAB).ceil() as usize + 1).clamp(1, MAX_BALLS);
    (0..count)
        .map(|k| {
            let t = if count == 1 {
                0.0
            } else {
                -reach + 2.0 * reach * k as f64 / (count - 1) as f64
            };
            (axis * t, radius)
        })
        .collect()
}

/// For the convex polytope with `vertices` and outward face `planes` (n·x ≤ d), grown by
/// `border`: one ball per slab across the vertices' longest extent, centred at the deepest
/// point of the slab's middle plane.
fn deepest_per_slab(
    vertices: &[Vector3<f64>],
    planes: &[(Vector3<f64>, f64)],
    border: f64,
) -> Vec<(Vector3<f64>, f64)> {
    let Some(first) = vertices.first() else {
        return Vec::new();
    };
    let (lo, hi) = vertices
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let axis = (hi - lo).imax();
    let count = (((hi[axis] - lo[axis]) / SLAB).ceil() as usize).clamp(1, MAX_BALLS);
    let mean = vertices.iter().sum::<Vector3<f64>>() / vertices.len() as f64;
    let depth = |p: &Vector3<f64>| {
        planes
            .iter()
            .map(|(n, d)| d - n.dot(p))
            .fold(f64::INFINITY, f64::min)
    };
    let across = [(axis + 1) % 3, (axis + 2) % 3];
    let width = (hi - lo).max();
    (0..count)
        .filter_map(|k| {
            let mut p = mean;
            p[axis] = lo[axis] + (hi[axis] - lo[axis]) * (k as f64 + 0.5) / count as f64;
            let mut best = depth(&p);
            // Depth is the least of affine functions, so concave: a compass search on the
            // middle plane climbs to its top.
            let mut step = 0.25 * width;
            while step > SEARCH_TOLERANCE {
                let moved = across
                    .iter()
                    .flat_map(|&i| [(i, step), (i, -step)])
                    .find_map(|(i, s)| {
                        let mut q = p;
                        q[i] += s;
                        let d = depth(&q);
                        (d > best).then_some((q, d))
                    });
                match moved {
                    Some((q, d)) => (p, best) = (q, d),
                    None => step *= 0.5,
                }
            }
            (best > 0.0).then_some((p, best + border))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::model::collision_elements;
    use crate::collision::spheres::tests::{arb_pose, arb_shape};
    use crate::collision::spheres::{Placement, Solid, Target};
    use crate::parry_convert;
    use crate::robot::Robot;
    use akl_scene::Shape;
    use akl_tsr::nalgebra::{Translation3, UnitQuaternion};
    use akl_tsr::Pose;
    use proptest::prelude::*;
    use std::sync::OnceLock;

    /// The Panda's collision elements with their inside balls.
    fn panda() -> &'static Vec<(Geometry, Spheres)> {
        static ELEMENTS: OnceLock<Vec<(Geometry, Spheres)>> = OnceLock::new();
        ELEMENTS.get_or_init(|| {
            let robot = Robot::panda().unwrap();
            collision_elements(&robot)
                .into_iter()
                .map(|(_, g, _)| {
                    let s = inside(&g);
                    (g, s)
                })
                .collect()
        })
    }

    /// How far `p` lies outside `geometry` grown by `margin` as parry shapes it (negative
    /// inside).
    fn outside(geometry: &Geometry, margin: f64, p: &Vector3<f64>) -> f64 {
        let (shape, _) = parry_convert::robot_shape(geometry, margin);
        let local = parry3d_f64::math::Vector::new(p.x, p.y, p.z);
        let projection = shape.as_ref().project_local_point(local, true);
        let d = (projection.point - local).length();
        if projection.is_inside {
            -d
        } else {
            d
        }
    }

    /// Points on the surface of every ball, in many directions.
    fn surface(spheres: &Spheres, grown: f64) -> Vec<Vector3<f64>> {
        let directions: Vec<Vector3<f64>> = (0..200)
            .map(|k| {
                // A Fibonacci sphere: directions spread evenly.
                let z = 1.0 - (2 * k + 1) as f64 / 200.0;
                let turn = k as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
                let r = (1.0 - z * z).sqrt();
                Vector3::new(r * turn.cos(), r * turn.sin(), z)
            })
            .collect();
        spheres
            .centres
            .iter()
            .zip(&spheres.radii)
            .flat_map(|(c, r)| directions.iter().map(move |u| c + u * (r + grown)))
            .collect()
    }

    #[test]
    fn every_panda_element_gets_balls_inside_it_as_large_as_their_centres_allow() {
        for (geometry, spheres) in panda() {
            assert!(!spheres.centres.is_empty(), "{geometry:?}");
            for margin in [0.0, 0.01] {
                let grown = spheres.grown(margin);
                let worst = surface(&grown, 0.0)
                    .iter()
                    .map(|p| outside(geometry, margin, p))
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!(
                    worst <= 1e-9,
                    "{geometry:?}: a ball reaches {worst} m outside"
                );
                // As large as they can be: a millimetre larger, each ball sticks out.
                for (centre, radius) in grown.centres.iter().zip(&grown.radii) {
                    let one = Spheres {
                        centres: vec![*centre],
                        radii: vec![*radius],
                    };
                    let loose = surface(&one, 1e-3)
                        .iter()
                        .map(|p| outside(geometry, margin, p))
                        .fold(f64::NEG_INFINITY, f64::max);
                    assert!(
                        loose > 1e-4,
                        "{geometry:?}: a ball is smaller than it can be at its centre"
                    );
                }
            }
        }
    }

    #[test]
    fn primitives_get_balls_inside_them() {
        for geometry in [
            Geometry::Box {
                size: [0.02, 0.3, 0.05],
            },
            Geometry::Capsule {
                radius: 0.04,
                length: 0.2,
            },
            Geometry::Cylinder {
                radius: 0.03,
                length: 0.25,
            },
            Geometry::Cylinder {
                radius: 0.1,
                length: 0.02,
            },
            Geometry::Sphere { radius: 0.05 },
        ] {
            let spheres = inside(&geometry);
            assert!(!spheres.centres.is_empty(), "{geometry:?}");
            let worst = surface(&spheres, 0.0)
                .iter()
                .map(|p| outside(&geometry, 0.0, p))
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(
                worst <= 1e-9,
                "{geometry:?}: a ball reaches {worst} m outside"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Wherever an inside ball reaches an object, parry's exact test finds the element
        /// touching it.
        #[test]
        fn a_ball_reaching_an_object_means_the_element_touches_it(
            element in 0usize..64,
            shape in arb_shape(),
            pose in arb_pose(0.3),
            at in arb_pose(0.1),
            margin in 0.0..0.02f64,
        ) {
            let (geometry, spheres) = &panda()[element % panda().len()];
            let target = Target::of(&shape, &pose);
            if target.reaches(&spheres.grown(margin), &Placement::of(&at)) {
                let (element_shape, _) = parry_convert::robot_shape(geometry, margin);
                let (object, fix) = parry_convert::object_shape(&shape, 0.0);
                prop_assert!(parry_convert::intersects(&element_shape, &at, &object, &(pose * fix)));
            }
        }
    }

    #[test]
    fn a_ball_in_an_object_is_found_and_none_far_from_it() {
        let (geometry, spheres) = &panda()[3];
        let block = Shape::Box {
            size: [0.02, 0.02, 0.02],
        };
        let at = Placement::of(&Pose::identity());
        let placed = |p: Vector3<f64>| {
            Target::of(
                &block,
                &Pose::from_parts(Translation3::from(p), UnitQuaternion::identity()),
            )
        };
        assert!(
            placed(spheres.centres[0]).reaches(spheres, &at),
            "{geometry:?}"
        );
        assert!(
            !placed(Vector3::new(1.0, 0.0, 0.0)).reaches(spheres, &at),
            "{geometry:?}"
        );
        let mesh = Target {
            solid: Solid::Other,
            ..placed(spheres.centres[0])
        };
        assert!(!mesh.reaches(spheres, &at), "a mesh's box is not the mesh");
    }
}
