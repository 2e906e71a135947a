//! Tests of the enclosing capsules: containment, volume against simple bounds, determinism.

use super::cells::SplitMix;
use super::fit::{circle_through, min_circle};
use super::*;
use akl_tsr::nalgebra::{Rotation3, Translation3};
use proptest::prelude::*;

type Triangle = [Point3<f64>; 3];

/// Fails unless every triangle has a capsule holding its three corners.
fn assert_encloses(triangles: &[Triangle], capsules: &[Capsule]) {
    for (i, t) in triangles.iter().enumerate() {
        assert!(
            capsules
                .iter()
                .any(|c| t.iter().all(|p| c.depth_outside(p) <= 0.0)),
            "triangle {i} {t:?} lies in no capsule of {capsules:?}"
        );
    }
}

fn total_volume(capsules: &[Capsule]) -> f64 {
    capsules.iter().map(Capsule::volume).sum()
}

/// The surface of the box from `lo` to `hi`: 12 triangles.
fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Vec<Triangle> {
    let corner = |i: usize| {
        Point3::new(
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        )
    };
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    faces
        .iter()
        .flat_map(|f| {
            let [a, b, c, d] = f.map(corner);
            [[a, b, c], [a, c, d]]
        })
        .collect()
}

/// The closed surface of a cylinder along z about the origin (side and both caps), with
/// `around` vertices on each circle and `along` rings of side triangles.
fn cylinder(radius: f64, length: f64, around: usize, along: usize) -> Vec<Triangle> {
    let rim = |i: usize, z: f64| {
        let angle = 2.0 * PI * (i % around) as f64 / around as f64;
        Point3::new(radius * angle.cos(), radius * angle.sin(), z)
    };
    let z = |j: usize| length * (j as f64 / along as f64 - 0.5);
    let mut triangles = Vec::new();
    for j in 0..along {
        for i in 0..around {
            let (p, q) = (rim(i, z(j)), rim(i + 1, z(j)));
            let (r, s) = (rim(i + 1, z(j + 1)), rim(i, z(j + 1)));
            triangles.push([p, q, r]);
            triangles.push([p, r, s]);
        }
    }
    for (end, top) in [(-0.5 * length, false), (0.5 * length, true)] {
        let centre = Point3::new(0.0, 0.0, end);
        for i in 0..around {
            let (p, q) = (rim(i, end), rim(i + 1, end));
            triangles.push(if top { [centre, p, q] } else { [centre, q, p] });
        }
    }
    triangles
}

/// Two bars of 0.3 x 0.04 x 0.04 m at right angles, meeting at a corner.
fn l_shape() -> Vec<Triangle> {
    let mut triangles = cuboid([0.0; 3], [0.3, 0.04, 0.04]);
    triangles.extend(cuboid([0.0; 3], [0.04, 0.3, 0.04]));
    triangles
}

/// A soup of triangles: each of `corners` is a triangle's cluster (an index into
/// `clusters`, each a centre and a size), its shape (0 and 1 plain, 2 all three corners
/// equal, 3 on a line) and its corners' offsets from the centre in cluster sizes.
fn soup(
    clusters: &[([f64; 3], f64)],
    corners: &[(prop::sample::Index, u8, [f64; 9])],
) -> Vec<Triangle> {
    corners
        .iter()
        .map(|(cluster, shape, offsets)| {
            let (centre, size) = clusters[cluster.index(clusters.len())];
            let corner = |k: usize| {
                Point3::new(
                    centre[0] + size * offsets[3 * k],
                    centre[1] + size * offsets[3 * k + 1],
                    centre[2] + size * offsets[3 * k + 2],
                )
            };
            let (a, b) = (corner(0), corner(1));
            match shape {
                2 => [a, a, a],
                3 => [a, b, a + (b - a) * 0.25],
                _ => [a, b, corner(2)],
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Whatever the triangles, each lies in a returned capsule, and the capsules are at
    /// most as many as asked for, with finite ends and radii at least 0.
    #[test]
    fn every_triangle_lies_in_one_capsule(
        clusters in prop::collection::vec(
            (prop::array::uniform3(-1.0f64..1.0), 0.001f64..0.3),
            1..4,
        ),
        corners in prop::collection::vec(
            (any::<prop::sample::Index>(), 0u8..4, prop::array::uniform9(-1.0f64..1.0)),
            1..40,
        ),
        count in 1usize..=4,
    ) {
        let triangles = soup(&clusters, &corners);
        let capsules = enclosing_capsules(&triangles, count);
        prop_assert!(!capsules.is_empty() && capsules.len() <= count);
        for c in &capsules {
            prop_assert!(c.radius.is_finite() && c.radius >= 0.0, "{c:?}");
            prop_assert!(c.a.coords.iter().chain(c.b.coords.iter()).all(|x| x.is_finite()));
        }
        assert_encloses(&triangles, &capsules);
    }
}

/// `n` triangles in a few clusters of assorted sizes, drawn with the generator seeded by
/// `seed`: enough triangles per cell that the cells' extreme corners leave some out.
fn big_soup(seed: u64, n: usize) -> Vec<Triangle> {
    let mut rng = SplitMix(seed);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.unit();
    let clusters: Vec<([f64; 3], f64, f64)> = (0..4)
        .map(|_| {
            let centre = [uniform(-0.5, 0.5), uniform(-0.5, 0.5), uniform(-0.5, 0.5)];
            (centre, uniform(0.01, 0.3), uniform(0.001, 0.05))
        })
        .collect();
    (0..n)
        .map(|i| {
            let (centre, spread, size) = clusters[i % clusters.len()];
            let middle = Vector3::new(
                centre[0] + spread * uniform(-1.0, 1.0),
                centre[1] + spread * uniform(-1.0, 1.0),
                centre[2] + spread * uniform(-1.0, 1.0),
            );
            [0; 3].map(|_| {
                Point3::from(
                    middle
                        + Vector3::new(
                            uniform(-size, size),
                            uniform(-size, size),
                            uniform(-size, size),
                        ),
                )
            })
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// The same for soups of hundreds of triangles, where containment rests on the final
    /// growth of the radii rather than on the fit.
    #[test]
    fn every_triangle_of_a_big_soup_lies_in_one_capsule(
        seed in any::<u64>(),
        n in 100usize..800,
        count in 1usize..=4,
    ) {
        let triangles = big_soup(seed, n);
        let capsules = enclosing_capsules(&triangles, count);
        prop_assert!(!capsules.is_empty() && capsules.len() <= count);
        assert_encloses(&triangles, &capsules);
    }
}

/// A closed tube of radius 0.05 m and length 0.2 m, turned and moved off the axes, is
/// held by one capsule of its radius, within 1.6 times its volume (a capsule of the
/// tube's radius and length is 4/3 of it).
#[test]
fn a_cylinder_gets_a_capsule_of_its_radius() {
    let place = Translation3::new(0.3, -0.2, 0.7) * Rotation3::from_euler_angles(0.4, -1.1, 0.3);
    let triangles: Vec<Triangle> = cylinder(0.05, 0.2, 32, 4)
        .into_iter()
        .map(|t| t.map(|p| place * p))
        .collect();
    let capsules = enclosing_capsules(&triangles, 1);
    assert_eq!(capsules.len(), 1);
    assert_encloses(&triangles, &capsules);
    let cylinder_volume = PI * 0.05f64.powi(2) * 0.2;
    let c = capsules[0];
    assert!((c.radius - 0.05).abs() <= 0.002, "{c:?}");
    assert!(
        c.volume() <= 1.6 * cylinder_volume,
        "{c:?}: {}",
        c.volume() / cylinder_volume
    );
}

/// Two capsules for an L of two bars take at most half the volume of one.
#[test]
fn an_l_shape_splits_into_its_bars() {
    let triangles = l_shape();
    let one = enclosing_capsules(&triangles, 1);
    let two = enclosing_capsules(&triangles, 2);
    assert_encloses(&triangles, &one);
    assert_encloses(&triangles, &two);
    assert_eq!(two.len(), 2);
    assert!(
        total_volume(&two) <= 0.5 * total_volume(&one),
        "{} against {}",
        total_volume(&two),
        total_volume(&one)
    );
}

/// Where two tubes meet at an angle, two capsules hold them about as tightly as one
/// capsule for each tube alone: the joint's triangles go to the tube they belong to.
#[test]
fn tubes_at_a_joint_each_get_their_own_capsule() {
    let first = cylinder(0.03, 0.3, 16, 4);
    let bend = Translation3::new(0.0, 0.0, 0.15)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), 1.0)
        * Translation3::new(0.0, 0.0, 0.125);
    let second: Vec<Triangle> = cylinder(0.03, 0.25, 16, 4)
        .into_iter()
        .map(|t| t.map(|p| bend * p))
        .collect();
    let alone = total_volume(&enclosing_capsules(&first, 1))
        + total_volume(&enclosing_capsules(&second, 1));
    let triangles: Vec<Triangle> = first.iter().chain(&second).copied().collect();
    let capsules = enclosing_capsules(&triangles, 2);
    assert_encloses(&triangles, &capsules);
    assert!(
        total_volume(&capsules) <= 1.05 * alone,
        "{} against {alone} for the tubes alone",
        total_volume(&capsules)
    );
}

/// The same input gives the same capsules.
#[test]
fn same_input_same_output() {
    let mut triangles = l_shape();
    triangles.extend(cylinder(0.02, 0.1, 12, 2));
    for count in 1..=4 {
        assert_eq!(
            enclosing_capsules(&triangles, count),
            enclosing_capsules(&triangles, count)
        );
    }
}

#[test]
fn no_triangles_no_capsules() {
    assert!(enclosing_capsules(&[], 3).is_empty());
}

/// A triangle shrunk to a point gets one capsule of about no size holding it.
#[test]
fn a_point_gets_a_point_capsule() {
    let p = Point3::new(0.1, -0.2, 0.3);
    let capsules = enclosing_capsules(&[[p, p, p]], 2);
    assert_eq!(capsules.len(), 1);
    assert!(capsules[0].depth_outside(&p) <= 0.0);
    assert!(capsules[0].radius <= 1e-6 && capsules[0].volume() < 1e-15);
}

#[test]
fn volume_and_depth_of_a_capsule() {
    let c = Capsule {
        a: Point3::new(0.0, 0.0, 0.0),
        b: Point3::new(0.0, 0.0, 2.0),
        radius: 0.5,
    };
    let expected = PI * 0.25 * 2.0 + 4.0 / 3.0 * PI * 0.125;
    assert!((c.volume() - expected).abs() < 1e-12);
    assert!((c.depth_outside(&Point3::new(0.0, 0.0, 1.0)) + 0.5).abs() < 1e-12);
    assert!((c.depth_outside(&Point3::new(2.0, 0.0, 1.0)) - 1.5).abs() < 1e-12);
    assert!((c.depth_outside(&Point3::new(0.0, 0.0, -1.0)) - 0.5).abs() < 1e-12);
}

proptest! {
    /// The circle holds every point and is no larger than the smallest circle through two
    /// or three of them that holds them all.
    #[test]
    fn the_smallest_circle_is_the_smallest(
        points in prop::collection::vec(prop::array::uniform2(-1.0f64..1.0), 1..10),
    ) {
        let (centre, r2) = min_circle(&points);
        let d2 = |p: [f64; 2], c: [f64; 2]| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
        for p in &points {
            prop_assert!(d2(*p, centre) <= r2 * (1.0 + 1e-9) + 1e-15);
        }
        let holds = |(c, r2): ([f64; 2], f64)| {
            points.iter().all(|p| d2(*p, c) <= r2 * (1.0 + 1e-9) + 1e-15)
        };
        let mut smallest = f64::INFINITY;
        for (i, &p) in points.iter().enumerate() {
            for (j, &q) in points.iter().enumerate().skip(i) {
                let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                if holds((mid, d2(p, mid))) {
                    smallest = smallest.min(d2(p, mid));
                }
                for &r in &points[j..] {
                    let circle = circle_through(p, q, r);
                    if holds(circle) {
                        smallest = smallest.min(circle.1);
                    }
                }
            }
        }
        prop_assert!(r2 <= smallest * (1.0 + 1e-9) + 1e-15, "{r2} against {smallest}");
    }
}
