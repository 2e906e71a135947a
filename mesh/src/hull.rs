//! Convex hulls: what a mesh object is planned and simulated as.

use crate::MeshError;
use akl_tsr::nalgebra::{Point3, Vector3};
use parry3d::math::Vector;
use parry3d::shape::{ConvexPolyhedron, Shape as _};
use std::path::Path;

/// The convex hull of a set of points, translated so that the middle of its bounding box is
/// the origin: a convex solid as AKL's objects are (every shape is centred on its frame).
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexHull {
    /// The hull's vertices, about the middle of its bounding box (metres).
    pub vertices: Vec<Point3<f64>>,
    /// Its faces as triangles of vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Where the middle of the bounding box was in the points' own frame: the hull is the
    /// points moved by minus this.
    pub offset: Vector3<f64>,
    /// Half the bounding box's sides.
    pub half_extents: Vector3<f64>,
    /// Its volume (m³).
    pub volume: f64,
    /// Its centre of mass as a uniform solid, in the hull's (centred) frame.
    pub centre_of_mass: Point3<f64>,
    /// Its outline seen from above: the convex polygon of the vertices projected on the x-y
    /// plane, counter-clockwise.
    pub outline: Vec<[f64; 2]>,
}

impl ConvexHull {
    /// The hull of `points`; `path` names their file in errors.
    pub fn of(points: &[Point3<f64>], path: &Path) -> Result<ConvexHull, MeshError> {
        let flat = || MeshError::Flat {
            path: path.to_path_buf(),
            points: points.len(),
        };
        if points.len() < 4 {
            return Err(flat());
        }
        let as_parry: Vec<Vector> = points
            .iter()
            .map(|p| Vector::new(p.x as f32, p.y as f32, p.z as f32))
            .collect();
        let (vertices, triangles) =
            parry3d::transformation::try_convex_hull(&as_parry).map_err(|_| flat())?;
        let vertices: Vec<Point3<f64>> = vertices
            .iter()
            .map(|v| Point3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z)))
            .collect();
        let (lo, hi) = vertices.iter().fold(
            (
                Vector3::repeat(f64::INFINITY),
                Vector3::repeat(f64::NEG_INFINITY),
            ),
            |(lo, hi), v| (lo.inf(&v.coords), hi.sup(&v.coords)),
        );
        let offset = 0.5 * (lo + hi);
        let vertices: Vec<Point3<f64>> = vertices.iter().map(|v| v - offset).collect();
        let polyhedron = ConvexPolyhedron::from_convex_hull(
            &vertices
                .iter()
                .map(|v| Vector::new(v.x as f32, v.y as f32, v.z as f32))
                .collect::<Vec<_>>(),
        )
        .ok_or_else(flat)?;
        let mass = polyhedron.mass_properties(1.0);
        let volume = f64::from(mass.mass());
        if volume.is_nan() || volume <= 0.0 || triangles.len() < 4 {
            return Err(flat());
        }
        let com = mass.local_com;
        let outline = outline(&vertices);
        Ok(ConvexHull {
            outline,
            vertices,
            triangles,
            offset,
            half_extents: 0.5 * (hi - lo),
            volume,
            centre_of_mass: Point3::new(f64::from(com.x), f64::from(com.y), f64::from(com.z)),
        })
    }

    /// The hull of the mesh file at `path` (see [`crate::load`]).
    pub fn from_file(path: &Path) -> Result<ConvexHull, MeshError> {
        let mesh = crate::load(path)?;
        ConvexHull::of(&mesh.vertices, path)
    }
}

/// The convex polygon, counter-clockwise, of `points` projected on the x-y plane (Andrew's
/// monotone chain). Written here because parry3d keeps its 2D hull to itself in 3D builds.
fn outline(points: &[Point3<f64>]) -> Vec<[f64; 2]> {
    let mut p: Vec<[f64; 2]> = points.iter().map(|v| [v.x, v.y]).collect();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in [false, true] {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &[f64; 2]>> = if pass {
            Box::new(p.iter().rev())
        } else {
            Box::new(p.iter())
        };
        for &q in ordered {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The corners of a box of sides `s` with its lowest corner at `at`, and its face centres
    /// (points inside the hull that must not become vertices).
    fn box_points(s: [f64; 3], at: [f64; 3]) -> Vec<Point3<f64>> {
        let mut points: Vec<Point3<f64>> = (0..8)
            .map(|i| {
                Point3::new(
                    at[0] + s[0] * f64::from(i & 1),
                    at[1] + s[1] * f64::from((i >> 1) & 1),
                    at[2] + s[2] * f64::from((i >> 2) & 1),
                )
            })
            .collect();
        points.push(Point3::new(at[0] + 0.5 * s[0], at[1] + 0.5 * s[1], at[2]));
        points
    }

    #[test]
    fn a_box_off_its_origin_is_centred_with_its_volume_and_centre() {
        let hull = ConvexHull::of(
            &box_points([0.04, 0.02, 0.1], [1.0, 2.0, 3.0]),
            Path::new("b"),
        )
        .unwrap();
        assert_eq!(hull.vertices.len(), 8);
        assert!(
            (hull.volume - 0.04 * 0.02 * 0.1).abs() < 1e-9,
            "{}",
            hull.volume
        );
        assert!((hull.offset - Vector3::new(1.02, 2.01, 3.05)).norm() < 1e-6);
        assert!((hull.half_extents - Vector3::new(0.02, 0.01, 0.05)).norm() < 1e-6);
        assert!(hull.centre_of_mass.coords.norm() < 1e-6);
        // Seen from above, a 4 x 2 cm rectangle, counter-clockwise.
        assert_eq!(hull.outline.len(), 4);
        let area: f64 = (0..4)
            .map(|i| {
                let (a, b) = (hull.outline[i], hull.outline[(i + 1) % 4]);
                0.5 * (a[0] * b[1] - a[1] * b[0])
            })
            .sum();
        // Single precision, as parry computes the hull.
        assert!((area - 0.04 * 0.02).abs() < 1e-8, "{area}");
    }

    #[test]
    fn points_on_a_plane_have_no_hull() {
        let flat = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
        ];
        let e = ConvexHull::of(&flat, Path::new("flat.stl")).unwrap_err();
        assert!(e.to_string().contains("flat.stl"), "{e}");
    }
}
