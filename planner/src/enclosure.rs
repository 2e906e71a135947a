//! The collision model of links that the URDF gives as meshes: per link, the convex hull of
//! its collision meshes grown by just enough to hold every vertex of its collision *and*
//! visual meshes, inside a capsule used to cull.
//!
//! Whatever touches the real link touches its surface, and every surface point lies in the
//! grown hull (a convex shape holding all the vertices holds every triangle), so a model free
//! of an obstacle proves the real link free of it. The vendor's collision meshes are coarse
//! hulls of a few hundred triangles, so exact tests stay cheap; the capsule around each hull
//! lets most pairs be ruled out by a segment distance before any exact test (the checks of
//! [`crate::collision`]).

use crate::geometry::{Geometry, LinkShape, RoundHull, ShapeRole};
use crate::line::distance_to_segment;
use crate::meshes::{LinkMesh, MeshRole};
use akl_mesh::Capsule;
use akl_tsr::nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};
use akl_tsr::Pose;
use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQuery;
use std::sync::Arc;

/// Longest triangle edge the capsule fitter sees (metres): a triangle must lie in one
/// capsule, and cutting long slivers lets the fit follow the shape.
pub(crate) const MAX_EDGE: f64 = 0.01;

/// The grown hull holding `meshes` (all of one link, in its frame), as a collision shape;
/// `None` when the meshes span no volume. The hull is simplified to [`HULL_TOLERANCE`] (the
/// tests' default; robots choose a tolerance per link through [`enclose_within`]).
#[cfg(test)]
pub(crate) fn enclose(meshes: &[&LinkMesh]) -> Option<LinkShape> {
    enclose_within(meshes, HULL_TOLERANCE)
}

/// `enclose` with the hull simplified until the dropped vertices reach at most `tolerance`
/// beyond it (or [`MAX_HULL_VERTICES`] are kept): the border, which grows the hull in every
/// direction, is then about that small.
pub(crate) fn enclose_within(meshes: &[&LinkMesh], tolerance: f64) -> Option<LinkShape> {
    let collision: Vec<&LinkMesh> = meshes
        .iter()
        .copied()
        .filter(|m| m.role == MeshRole::Collision)
        .collect();
    // The vendor's collision meshes when there are any (coarse: few vertices), else all.
    let base = if collision.is_empty() {
        meshes
    } else {
        &collision[..]
    };
    let points: Vec<Point3<f64>> = base.iter().flat_map(|m| m.mesh.vertices.clone()).collect();
    // akl-mesh's hull, moved back from its bounding box's centre; flat meshes have none.
    let named = std::path::Path::new(&base.first()?.uri);
    let hull = akl_mesh::ConvexHull::of(&points, named).ok()?;
    let full: Vec<Point3<f64>> = hull.vertices.iter().map(|v| v + hull.offset).collect();
    let (vertices, triangles) = simplified(&full, tolerance)?;
    let faces: Vec<[Point3<f64>; 3]> = triangles
        .iter()
        .map(|t| t.map(|i| vertices[i as usize]))
        .collect();
    // The border: how far the furthest vertex of any mesh lies outside the hull, plus what
    // single precision may lose.
    let border =
        furthest_outside(&distinct_vertices(meshes), &faces).map_or(0.0, |(_, d)| d) + 1e-6;
    // The culling capsule holds the hull's vertices, then grows by the border.
    let capsule = akl_mesh::enclosing_capsules(&subdivided(faces.iter().copied(), MAX_EDGE), 1)
        .into_iter()
        .next()?;
    let frame = capsule_frame(&capsule);
    let inverse = frame.inverse();
    Some(LinkShape {
        geometry: Geometry::RoundHull(Arc::new(RoundHull {
            vertices: vertices.iter().map(|v| inverse * v).collect(),
            triangles,
            border,
            half_length: 0.5 * (capsule.b - capsule.a).norm(),
            radius: capsule.radius + border,
        })),
        origin: frame,
        role: ShapeRole::Enclosure,
    })
}

/// A convex polytope: its vertices and its faces as triangles of vertex indices.
type Polytope = (Vec<Point3<f64>>, Vec<[u32; 3]>);

/// Most vertices a link's hull keeps: every exact test scans them (parry's support function),
/// and the border grows by what the dropped ones reach beyond. Chosen by measurement
/// (BENCHMARKS.md, "The real Panda's geometry"): keeping every vertex (up to 152) made a
/// full-arm check 4.4 µs; 16, 24, 32 and 48 cost 2.6–3.2 µs alike while the model's mean
/// stand-off fell from 8.4 to 2.8 mm, so 48.
pub(crate) const MAX_HULL_VERTICES: usize = 48;

/// How far the dropped vertices may reach beyond the kept ones' hull before more are kept
/// (metres).
pub(crate) const HULL_TOLERANCE: f64 = 0.002;

/// [`HULL_TOLERANCE`] for the links a revolute gripper joint swings (a linkage's knuckles,
/// bars and fingertips, such as the Robotiq 2F-85's): they pass within millimetres of what the
/// pads close on by design (the inner knuckles sweep in over a grasped block's top edge), so a
/// border of 2 mm on every side of their hulls (the 2F-85's knuckle links kept 17–21 vertices
/// and grew 1.7–2.1 mm) forbids grasps the real linkage clears. At 0.25 mm they keep 35–48
/// vertices and grow 0.7–1.0 mm (what is left is mostly the visual meshes reaching past the
/// collision meshes). Prismatic fingers are not swung: the Panda's hulls are unchanged.
pub(crate) const LINKAGE_HULL_TOLERANCE: f64 = 0.000_25;

/// A hull of a subset of the convex polytope `vertices`: starting from the extreme vertices in
/// 14 directions, the vertex furthest outside the current hull is added until none is further
/// than `tolerance` or [`MAX_HULL_VERTICES`] are kept. The caller grows it by what is left
/// outside.
fn simplified(vertices: &[Point3<f64>], tolerance: f64) -> Option<Polytope> {
    let mut kept: Vec<usize> = Vec::new();
    for dx in [-1.0, 0.0, 1.0] {
        for dy in [-1.0, 0.0, 1.0] {
            for dz in [-1.0, 0.0, 1.0] {
                let d = Vector3::new(dx, dy, dz);
                // The 6 axis and 8 diagonal directions.
                if d.iter().filter(|c| **c != 0.0).count() == 2 || d == Vector3::zeros() {
                    continue;
                }
                let extreme = (0..vertices.len()).max_by(|&a, &b| {
                    vertices[a]
                        .coords
                        .dot(&d)
                        .total_cmp(&vertices[b].coords.dot(&d))
                })?;
                if !kept.contains(&extreme) {
                    kept.push(extreme);
                }
            }
        }
    }
    loop {
        let points: Vec<Vector> = kept
            .iter()
            .map(|&i| {
                let v = vertices[i];
                Vector::new(v.x, v.y, v.z)
            })
            .collect();
        let hull = parry3d_f64::transformation::try_convex_hull(&points).ok();
        let hull = hull.filter(|(_, t)| !t.is_empty());
        let worst = match &hull {
            Some((v, t)) => {
                let faces: Vec<[Point3<f64>; 3]> = t
                    .iter()
                    .map(|t| {
                        t.map(|i| {
                            let p = v[i as usize];
                            Point3::new(p.x, p.y, p.z)
                        })
                    })
                    .collect();
                furthest_outside(vertices, &faces)?
            }
            // Too few or flat: keep the vertex furthest from those kept.
            None => (0..vertices.len())
                .map(|i| {
                    let d = kept
                        .iter()
                        .map(|&k| (vertices[k] - vertices[i]).norm())
                        .fold(f64::INFINITY, f64::min);
                    (i, d)
                })
                .max_by(|a, b| a.1.total_cmp(&b.1))?,
        };
        let done =
            worst.1 <= tolerance || kept.len() >= MAX_HULL_VERTICES || kept.contains(&worst.0);
        match hull {
            Some((v, t)) if done => {
                let v = v.iter().map(|p| Point3::new(p.x, p.y, p.z)).collect();
                return Some((v, t));
            }
            None if kept.contains(&worst.0) => return None,
            _ => kept.push(worst.0),
        }
    }
}

/// The point of `points` furthest outside the convex polytope bounded by `faces` and how far
/// it lies (the last of equals, as `Iterator::max_by` picks; 0 when all are inside); `None`
/// for no points. The same as [`outside_distance`] of every point, without the exact distance
/// of a point that cannot be the furthest: the triangle of the face it lies furthest beyond
/// bounds its distance from above. Enclosing the Panda's meshes measured every vertex against
/// every face, 0.27 s of each start.
fn furthest_outside(points: &[Point3<f64>], faces: &[[Point3<f64>; 3]]) -> Option<(usize, f64)> {
    let planes: Vec<(Vector3<f64>, Point3<f64>)> = faces
        .iter()
        .map(|[a, b, c]| {
            let n = (b - a).cross(&(c - a));
            (n.try_normalize(0.0).unwrap_or_else(Vector3::zeros), *a)
        })
        .collect();
    let mut furthest: Option<(usize, f64)> = None;
    for (i, p) in points.iter().enumerate() {
        let mut beyond: Option<(usize, f64)> = None;
        for (k, (n, a)) in planes.iter().enumerate() {
            let s = n.dot(&(p - a));
            if s > 0.0 && beyond.is_none_or(|(_, most)| s > most) {
                beyond = Some((k, s));
            }
        }
        let distance = match beyond {
            None => 0.0,
            Some((k, _)) => {
                let above = point_triangle_distance(p, &faces[k]);
                if furthest.is_some_and(|(_, d)| above < d) {
                    continue;
                }
                faces
                    .iter()
                    .map(|t| point_triangle_distance(p, t))
                    .fold(f64::INFINITY, f64::min)
            }
        };
        if furthest.is_none_or(|(_, d)| distance >= d) {
            furthest = Some((i, distance));
        }
    }
    furthest
}

/// Every vertex of `meshes` once: mesh files repeat a vertex for each triangle it
/// belongs to, and measuring each copy against the hull was two fifths of loading a robot.
fn distinct_vertices(meshes: &[&LinkMesh]) -> Vec<Point3<f64>> {
    let mut keys: Vec<[u64; 3]> = meshes
        .iter()
        .flat_map(|m| &m.mesh.vertices)
        .map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.iter()
        .map(|k| {
            Point3::new(
                f64::from_bits(k[0]),
                f64::from_bits(k[1]),
                f64::from_bits(k[2]),
            )
        })
        .collect()
}

/// How far `p` lies outside the convex polytope bounded by `faces` (0 inside).
#[cfg(test)]
fn outside_distance(p: &Point3<f64>, faces: &[[Point3<f64>; 3]]) -> f64 {
    let outside = faces.iter().any(|[a, b, c]| {
        let n = (b - a).cross(&(c - a));
        n.dot(&(p - a)) > 0.0
    });
    if !outside {
        return 0.0;
    }
    faces
        .iter()
        .map(|t| point_triangle_distance(p, t))
        .fold(f64::INFINITY, f64::min)
}

/// The triangles cut (halving the longest edge, again and again) until no edge is longer
/// than `max_edge`: the pieces cover exactly the same surface.
pub(crate) fn subdivided(
    triangles: impl Iterator<Item = [Point3<f64>; 3]>,
    max_edge: f64,
) -> Vec<[Point3<f64>; 3]> {
    let mut out = Vec::new();
    let mut stack: Vec<[Point3<f64>; 3]> = Vec::new();
    for t in triangles {
        stack.push(t);
        while let Some(t) = stack.pop() {
            let edges = [(0, 1), (1, 2), (2, 0)].map(|(i, j)| (t[i] - t[j]).norm());
            let (longest, length) =
                edges.iter().enumerate().fold(
                    (0, 0.0),
                    |best, (k, &l)| if l > best.1 { (k, l) } else { best },
                );
            if length <= max_edge {
                out.push(t);
                continue;
            }
            let (i, j) = [(0, 1), (1, 2), (2, 0)][longest];
            let k = 3 - i - j;
            let mid = t[i] + 0.5 * (t[j] - t[i]);
            stack.push([t[i], mid, t[k]]);
            stack.push([mid, t[j], t[k]]);
        }
    }
    out
}

/// The frame of a capsule: centred on its segment, z along it.
pub(crate) fn capsule_frame(c: &Capsule) -> Pose {
    let axis = c.b - c.a;
    let rotation = if axis.norm() > 0.0 {
        UnitQuaternion::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
        })
    } else {
        UnitQuaternion::identity()
    };
    let centre = c.a + 0.5 * axis;
    Pose::from_parts(Translation3::from(centre.coords), rotation)
}

/// How far a link's model stands off its meshes: over points spread on the model's outer
/// surface, their distance to the nearest mesh point (metres).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StandOff {
    /// Mean over the sampled points.
    pub mean: f64,
    /// Largest.
    pub max: f64,
}

/// The stand-off of the grown hull `shape` from the triangles of `meshes` (one link's):
/// points spread on the hull's faces (about one per `spacing` metres), pushed out by the
/// border, and their distance to the nearest mesh point.
pub fn stand_off(shape: &LinkShape, meshes: &[&LinkMesh], spacing: f64) -> Option<StandOff> {
    let Geometry::RoundHull(hull) = &shape.geometry else {
        return None;
    };
    // The meshes as one parry mesh: its bounding-volume tree answers the nearest-point
    // queries (tens of thousands of triangles, thousands of points).
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for m in meshes {
        let offset = vertices.len() as u32;
        vertices.extend(m.mesh.vertices.iter().map(|v| Vector::new(v.x, v.y, v.z)));
        indices.extend(m.mesh.triangles.iter().map(|t| t.map(|i| i + offset)));
    }
    let surface = parry3d_f64::shape::TriMesh::new(vertices, indices).ok()?;
    let mut sum = 0.0;
    let mut max: f64 = 0.0;
    let mut n = 0usize;
    for t in &hull.triangles {
        let [a, b, c] = t.map(|i| shape.origin * hull.vertices[i as usize]);
        let normal = (b - a).cross(&(c - a));
        if normal.norm() < 1e-12 {
            continue;
        }
        let normal = normal.normalize();
        let steps = (((b - a).norm().max((c - a).norm())) / spacing)
            .ceil()
            .max(1.0) as usize;
        for i in 0..steps {
            for j in 0..steps - i {
                let (u, v) = (
                    (i as f64 + 1.0 / 3.0) / steps as f64,
                    (j as f64 + 1.0 / 3.0) / steps as f64,
                );
                let p = a + u * (b - a) + v * (c - a) + hull.border * normal;
                let at = Vector::new(p.x, p.y, p.z);
                let d = surface.distance_to_local_point(at, false);
                sum += d;
                max = max.max(d);
                n += 1;
            }
        }
    }
    (n > 0).then(|| StandOff {
        mean: sum / n as f64,
        max,
    })
}

/// The capsule that holds a shape, in the link frame: the capsule itself, or a grown hull's
/// holding capsule.
#[cfg(test)]
pub(crate) fn shape_capsule(s: &LinkShape) -> Option<Capsule> {
    let (radius, half_length) = match &s.geometry {
        Geometry::Capsule { radius, length } => (*radius, 0.5 * length),
        Geometry::RoundHull(h) => (h.radius, h.half_length),
        _ => return None,
    };
    let half = s.origin.rotation * Vector3::new(0.0, 0.0, half_length);
    let centre = Point3::from(s.origin.translation.vector);
    Some(Capsule {
        a: centre - half,
        b: centre + half,
        radius,
    })
}

/// Distance from `p` to the triangle `t` (exact: the nearest point may lie inside the
/// triangle, on an edge or at a corner).
pub fn point_triangle_distance(p: &Point3<f64>, t: &[Point3<f64>; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (ap - v * ab).norm();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (ap - w * ac).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - w * (c - b)).norm();
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        // A degenerate triangle: its nearest point is on an edge.
        return [(a, b), (b, c), (c, a)]
            .iter()
            .map(|(u, v)| distance_to_segment(&p.coords, &u.coords, &v.coords))
            .fold(f64::INFINITY, f64::min);
    }
    let (v, w) = (vb / denom, vc / denom);
    (ap - v * ab - w * ac).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mesh(role: MeshRole, vertices: Vec<Point3<f64>>, triangles: Vec<[u32; 3]>) -> LinkMesh {
        LinkMesh {
            link: 0,
            role,
            uri: String::new(),
            mesh: akl_mesh::TriMesh {
                vertices,
                triangles,
            },
        }
    }

    /// A box's eight corners and twelve faces.
    fn box_mesh(role: MeshRole, half: [f64; 3], shift: [f64; 3]) -> LinkMesh {
        let vertices = (0..8)
            .map(|i| {
                Point3::new(
                    shift[0] + if i & 1 == 0 { -half[0] } else { half[0] },
                    shift[1] + if i & 2 == 0 { -half[1] } else { half[1] },
                    shift[2] + if i & 4 == 0 { -half[2] } else { half[2] },
                )
            })
            .collect();
        let triangles = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        mesh(role, vertices, triangles)
    }

    #[test]
    fn each_vertex_is_measured_once() {
        let solid = box_mesh(MeshRole::Collision, [0.05, 0.03, 0.1], [0.0; 3]);
        // The same box as a triangle soup, every corner repeated for each of its triangles.
        let corners = &solid.mesh.vertices;
        let soup: Vec<Point3<f64>> = solid
            .mesh
            .triangles
            .iter()
            .flat_map(|t| t.map(|i| corners[i as usize]))
            .collect();
        let n = soup.len() as u32;
        let triangles = (0..n / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let soup = mesh(MeshRole::Visual, soup, triangles);
        let key = |p: &Point3<f64>| [p.x, p.y, p.z].map(f64::to_bits);
        let mut distinct = distinct_vertices(&[&solid, &soup]);
        let mut expected = corners.clone();
        distinct.sort_by_key(key);
        expected.sort_by_key(key);
        assert_eq!(distinct, expected);
    }

    #[test]
    fn the_grown_hull_holds_a_visual_mesh_that_pokes_out() {
        let collision = box_mesh(MeshRole::Collision, [0.05, 0.03, 0.1], [0.0; 3]);
        // The visual box reaches 3 mm past the collision box along x.
        let visual = box_mesh(MeshRole::Visual, [0.053, 0.02, 0.05], [0.0; 3]);
        let shape = enclose(&[&collision, &visual]).unwrap();
        let Geometry::RoundHull(hull) = &shape.geometry else {
            panic!("{shape:?}")
        };
        assert!((hull.border - 0.003).abs() < 1e-5, "{}", hull.border);
        // Every vertex of both meshes lies in the grown hull and in the culling capsule.
        let capsule = shape_capsule(&shape).unwrap();
        let faces: Vec<[Point3<f64>; 3]> = hull
            .triangles
            .iter()
            .map(|t| t.map(|i| shape.origin * hull.vertices[i as usize]))
            .collect();
        for v in collision.mesh.vertices.iter().chain(&visual.mesh.vertices) {
            assert!(outside_distance(v, &faces) <= hull.border, "{v}");
            assert!(capsule.depth_outside(v) <= 0.0, "{v}");
        }
        // Tight: the hull is the collision box, no bigger.
        let so = stand_off(&shape, &[&collision, &visual], 0.01).unwrap();
        // (to what parry's single-precision nearest points resolve)
        assert!(so.max <= hull.border + 1e-5, "{so:?}");
    }

    /// A round mesh (a cylinder of 32 sides, 1 cm in radius): at 2 mm the hull keeps few of its vertices and
    /// grows by what the dropped ones reach; at the linkage's 0.25 mm it keeps more and grows
    /// less. Either way every vertex lies within the grown hull.
    #[test]
    fn a_finer_tolerance_keeps_more_vertices_and_grows_less() {
        let sides: u32 = 32;
        let (radius, half) = (0.01, 0.03);
        let mut vertices = Vec::new();
        for k in 0..sides {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
            for z in [-half, half] {
                vertices.push(Point3::new(radius * a.cos(), radius * a.sin(), z));
            }
        }
        let mut triangles = Vec::new();
        for k in 0..sides {
            let (a, b) = (2 * k, 2 * ((k + 1) % sides));
            triangles.push([a, b, a + 1]);
            triangles.push([b, b + 1, a + 1]);
        }
        let cylinder = mesh(MeshRole::Collision, vertices, triangles);
        let grown = |tolerance: f64| {
            let shape = enclose_within(&[&cylinder], tolerance).unwrap();
            let Geometry::RoundHull(hull) = &shape.geometry else {
                panic!("{shape:?}")
            };
            let faces: Vec<[Point3<f64>; 3]> = hull
                .triangles
                .iter()
                .map(|t| t.map(|i| shape.origin * hull.vertices[i as usize]))
                .collect();
            for v in &cylinder.mesh.vertices {
                assert!(outside_distance(v, &faces) <= hull.border, "{v}");
            }
            (hull.vertices.len(), hull.border)
        };
        let (coarse, fine) = (grown(HULL_TOLERANCE), grown(LINKAGE_HULL_TOLERANCE));
        assert!(fine.0 > coarse.0, "{coarse:?} {fine:?}");
        assert!(fine.1 <= LINKAGE_HULL_TOLERANCE + 1e-6, "{fine:?}");
        assert!(coarse.1 > 2.0 * fine.1, "{coarse:?} {fine:?}");
        assert_eq!(
            enclose(&[&cylinder]).unwrap(),
            enclose_within(&[&cylinder], HULL_TOLERANCE).unwrap()
        );
    }

    #[test]
    fn flat_meshes_have_no_hull() {
        let flat = mesh(
            MeshRole::Visual,
            vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2]],
        );
        assert!(enclose(&[&flat]).is_none());
    }

    #[test]
    fn subdividing_keeps_the_area_and_bounds_the_edges() {
        let t = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.3, 0.0, 0.0),
            Point3::new(0.0, 0.05, 0.0),
        ];
        let area = |t: &[Point3<f64>; 3]| 0.5 * (t[1] - t[0]).cross(&(t[2] - t[0])).norm();
        let pieces = subdivided(std::iter::once(t), 0.01);
        let total: f64 = pieces.iter().map(area).sum();
        assert!((total - area(&t)).abs() < 1e-12);
        for p in &pieces {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                assert!((p[i] - p[j]).norm() <= 0.01);
            }
        }
    }

    proptest! {
        #[test]
        fn triangle_distance_is_the_least_over_the_triangle(
            corners in prop::array::uniform9(-1.0f64..1.0),
            p in prop::array::uniform3(-2.0f64..2.0),
        ) {
            let t = [
                Point3::new(corners[0], corners[1], corners[2]),
                Point3::new(corners[3], corners[4], corners[5]),
                Point3::new(corners[6], corners[7], corners[8]),
            ];
            let p = Point3::new(p[0], p[1], p[2]);
            let d = point_triangle_distance(&p, &t);
            // No point of the triangle is nearer, and some point is (within the grid's step).
            let mut least = f64::INFINITY;
            let steps = 60;
            for i in 0..=steps {
                for j in 0..=steps - i {
                    let (u, v) = (i as f64 / steps as f64, j as f64 / steps as f64);
                    let q = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
                    least = least.min((p - q).norm());
                }
            }
            prop_assert!(d <= least + 1e-9, "{d} > {least}");
            let side = (t[1] - t[0]).norm().max((t[2] - t[0]).norm());
            prop_assert!(least - d <= side / steps as f64 + 1e-9, "{least} vs {d}");
        }

        /// The furthest point outside a hull, found without measuring every point exactly, is
        /// the one (and the distance) that measuring every point gives, ties included.
        #[test]
        fn the_furthest_point_outside_is_found_as_by_measuring_every_point(
            corners in prop::collection::vec(prop::array::uniform3(-0.1f64..0.1), 8..30),
            points in prop::collection::vec(prop::array::uniform3(-0.15f64..0.15), 1..200),
            repeat in 0usize..200,
        ) {
            let at = |c: &[f64; 3]| Point3::new(c[0], c[1], c[2]);
            let hull: Vec<Vector> = corners.iter().map(|c| Vector::new(c[0], c[1], c[2])).collect();
            let Ok((v, t)) = parry3d_f64::transformation::try_convex_hull(&hull) else {
                return Ok(());
            };
            let faces: Vec<[Point3<f64>; 3]> = t
                .iter()
                .map(|t| t.map(|i| Point3::new(v[i as usize].x, v[i as usize].y, v[i as usize].z)))
                .collect();
            let mut points: Vec<Point3<f64>> = points.iter().map(at).collect();
            // A point again, so that the furthest may come twice.
            points.push(points[repeat % points.len()]);
            let expected = points
                .iter()
                .enumerate()
                .map(|(i, p)| (i, outside_distance(p, &faces)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            prop_assert_eq!(furthest_outside(&points, &faces), expected);
        }
    }
}
