//! The reference of a line's pure constraint keyframes: the fixed object the line passes over.
//!
//! The thesis grounds every keyframe on the key object of the next interaction (§3.2.4). For a
//! line that is *about* something else — carry the part in a line over the row of scanners —
//! that rule ties the line to the shelf the part goes to next, so the line does not follow the
//! scanners when they are moved. The rule here: a pure constraint keyframe (a line boundary
//! that is not at a gripper command) is grounded on the **fixed object whose outline, seen from
//! above, the line's path crosses, while the lowest point of what moves (the held object's
//! bottom, or the tool centre point when nothing is held) runs at most [`PASS_OVER_HEIGHT`]
//! above that object's top and not below its bottom**; of several, the one whose centre is
//! nearest the path's midpoint in the horizontal plane. Otherwise — no world with shapes, no
//! fixed object under the path, or the path high above everything — the thesis rule stands.
//! Combined keyframes keep their interaction's reference, since the interaction is what they
//! are about.
//!
//! Only objects whose shape and fixedness the task's world gives take part: a recording without
//! a world keeps the thesis rule.

use super::reference::SceneObject;
use akl_scene::Shape;
use akl_tsr::nalgebra::{Vector2, Vector3};

/// How high (metres) above a fixed object's top the lowest point of what moves may run for
/// the line to count as passing over it: 0.10. Chosen by measurement with `cargo test -p
/// akl-learn --test fidelity pass_over_survey -- --ignored --nocapture`, which learns the
/// built-in inspection task from the careful and the first-time simulated teachers (10 seeds
/// each) and prints the clearance of the learned line over each fixed object it crosses: 5.0
/// to 5.3 cm over the three scanners, 15.0 to 15.3 cm over the table, nothing else crossed.
/// 0.10 m sits halfway, about 5 cm from both; a line carried a hand's width above a fixture is
/// about it, one carried at shelf height over the whole table is not.
pub(crate) const PASS_OVER_HEIGHT: f64 = 0.10;

/// A straight motion between two frames, as the rule needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinePath {
    /// Tool centre point at the line's first frame.
    pub from: Vector3<f64>,
    /// Tool centre point at the line's last frame.
    pub to: Vector3<f64>,
    /// Height of the lowest point of what moves at the first frame.
    pub low_from: f64,
    /// Height of the lowest point of what moves at the last frame.
    pub low_to: f64,
    /// A frame of the line, at which the objects' poses are read.
    pub frame: usize,
}

/// How the path runs over one object: the clearance above its top where it crosses and the
/// horizontal distance of its centre from the path's midpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Index into the objects.
    pub object: usize,
    /// Lowest height of what moves over the object's outline, minus the object's top (m).
    pub clearance: f64,
    /// Highest height of what moves over the outline, minus the object's bottom (m).
    pub above_bottom: f64,
    /// Horizontal distance of the object's centre from the path's midpoint (m).
    pub from_midpoint: f64,
}

/// Every fixed object with a known shape whose outline the path crosses (other than `held`).
pub fn crossings(objects: &[SceneObject], path: &LinePath, held: Option<usize>) -> Vec<Crossing> {
    let middle = ((path.from + path.to) / 2.0).xy();
    objects
        .iter()
        .enumerate()
        .filter(|(i, o)| Some(*i) != held && o.movable == Some(false))
        .filter_map(|(i, o)| {
            let shape = o.shape.as_ref()?;
            let pose = o.pose(path.frame);
            let local = |p: &Vector3<f64>| pose.inverse_transform_point(&(*p).into()).xy().coords;
            let (s0, s1) = outline_interval(shape, local(&path.from), local(&path.to))?;
            let low = |s: f64| path.low_from + (path.low_to - path.low_from) * s;
            let (lowest, highest) = (low(s0).min(low(s1)), low(s0).max(low(s1)));
            Some(Crossing {
                object: i,
                clearance: lowest - shape.top(pose),
                above_bottom: highest - shape.bottom(pose),
                from_midpoint: (pose.translation.vector.xy() - middle).norm(),
            })
        })
        .collect()
}

/// The fixed object the path passes over (see the module docs), if any.
pub(crate) fn passed_over(
    objects: &[SceneObject],
    path: &LinePath,
    held: Option<usize>,
) -> Option<usize> {
    crossings(objects, path, held)
        .into_iter()
        .filter(|c| c.clearance <= PASS_OVER_HEIGHT && c.above_bottom >= 0.0)
        .min_by(|a, b| a.from_midpoint.total_cmp(&b.from_midpoint))
        .map(|c| c.object)
}

/// The part `[s0, s1]` ⊂ [0, 1] of the segment `a`→`b` (in the shape's frame, seen from above)
/// inside the shape's outline, or `None` when it misses. A segment that is a point (a vertical
/// path) is inside or not as a whole.
fn outline_interval(shape: &Shape, a: Vector2<f64>, b: Vector2<f64>) -> Option<(f64, f64)> {
    let d = b - a;
    let (s0, s1) = match *shape {
        Shape::Box { size } => {
            let mut range = (0.0f64, 1.0f64);
            for axis in 0..2 {
                let half = size[axis] / 2.0;
                if d[axis].abs() < 1e-12 {
                    if a[axis].abs() > half {
                        return None;
                    }
                    continue;
                }
                let (t0, t1) = ((-half - a[axis]) / d[axis], (half - a[axis]) / d[axis]);
                range = (range.0.max(t0.min(t1)), range.1.min(t0.max(t1)));
            }
            range
        }
        Shape::Cylinder { radius, .. }
        | Shape::Capsule { radius, .. }
        | Shape::Sphere { radius } => {
            let dd = d.norm_squared();
            if dd < 1e-24 {
                return (a.norm() <= radius).then_some((0.0, 1.0));
            }
            // |a + t·d|² = r²
            let half_b = a.dot(&d) / dd;
            let c = (a.norm_squared() - radius * radius) / dd;
            let disc = half_b * half_b - c;
            if disc < 0.0 {
                return None;
            }
            let root = disc.sqrt();
            ((-half_b - root).max(0.0), (-half_b + root).min(1.0))
        }
        Shape::Mesh { ref hull, .. } => {
            // The segment clipped by each edge of the convex outline (counter-clockwise).
            let outline = hull.as_ref().map_or(&[][..], |h| &h.outline[..]);
            let mut range = (0.0f64, 1.0f64);
            for (i, p) in outline.iter().enumerate() {
                let q = outline[(i + 1) % outline.len()];
                let normal = Vector2::new(q[1] - p[1], p[0] - q[0]);
                // Inside where (a + t·d − p)·normal ≤ 0.
                let at = (a - Vector2::new(p[0], p[1])).dot(&normal);
                let rate = d.dot(&normal);
                if rate.abs() < 1e-15 {
                    if at > 0.0 {
                        return None;
                    }
                    continue;
                }
                let t = -at / rate;
                if rate > 0.0 {
                    range.1 = range.1.min(t);
                } else {
                    range.0 = range.0.max(t);
                }
            }
            if outline.len() < 3 {
                return None;
            }
            range
        }
    };
    (s0 <= s1).then_some((s0, s1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz;
    use std::borrow::Cow;

    fn object(name: &str, p: [f64; 3], size: [f64; 3], movable: bool) -> SceneObject<'static> {
        SceneObject {
            name: name.into(),
            poses: Cow::Owned(vec![pose_from_xyz(p)]),
            shape: Some(Shape::Box { size }),
            movable: Some(movable),
        }
    }

    fn path(from: [f64; 3], to: [f64; 3], low: f64) -> LinePath {
        LinePath {
            from: Vector3::from(from),
            to: Vector3::from(to),
            low_from: low,
            low_to: low,
            frame: 0,
        }
    }

    /// A conveyor of three rollers on a bench, the line carried along it.
    fn conveyor() -> Vec<SceneObject<'static>> {
        vec![
            object("bench", [0.4, 0.0, -0.02], [1.0, 1.2, 0.04], false),
            object("roller_a", [0.3, -0.2, 0.03], [0.06, 0.2, 0.06], false),
            object("roller_b", [0.4, -0.2, 0.03], [0.06, 0.2, 0.06], false),
            object("roller_c", [0.5, -0.2, 0.03], [0.06, 0.2, 0.06], false),
            object("crate", [0.41, -0.2, 0.1], [0.05, 0.05, 0.05], true),
        ]
    }

    #[test]
    fn a_line_over_a_row_is_grounded_on_the_object_under_its_middle() {
        let objs = conveyor();
        // Along x over the rollers, 4 cm above their tops.
        let p = path([0.2, -0.2, 0.2], [0.6, -0.2, 0.2], 0.1);
        let names: Vec<_> = crossings(&objs, &p, None)
            .iter()
            .map(|c| objs[c.object].name.as_str())
            .collect();
        assert_eq!(names, vec!["bench", "roller_a", "roller_b", "roller_c"]);
        assert_eq!(passed_over(&objs, &p, None), Some(2));
        // The movable crate is never a reference, even when held or under the path.
        assert_eq!(passed_over(&objs, &p, Some(4)), Some(2));
    }

    #[test]
    fn a_line_too_high_beside_or_under_keeps_the_thesis_rule() {
        let objs = conveyor();
        // 25 cm above the rollers (and the bench): too high.
        assert_eq!(
            passed_over(&objs, &path([0.2, -0.2, 0.4], [0.6, -0.2, 0.4], 0.31), None),
            None
        );
        // Beside the rollers, low over the bench: the bench.
        assert_eq!(
            passed_over(&objs, &path([0.2, 0.3, 0.1], [0.6, 0.3, 0.1], 0.05), None),
            Some(0)
        );
        // Off the bench altogether.
        assert_eq!(
            passed_over(&objs, &path([1.0, 0.0, 0.1], [1.2, 0.0, 0.1], 0.0), None),
            None
        );
        // Under a fixed overhang: not over it.
        let shelf = vec![object("shelf", [0.4, 0.0, 0.5], [0.3, 0.3, 0.02], false)];
        assert_eq!(
            passed_over(&shelf, &path([0.2, 0.0, 0.3], [0.6, 0.0, 0.3], 0.25), None),
            None
        );
        // No shapes known: nothing.
        let bare: Vec<_> = conveyor()
            .into_iter()
            .map(|mut o| {
                o.shape = None;
                o
            })
            .collect();
        assert_eq!(
            passed_over(&bare, &path([0.2, -0.2, 0.2], [0.6, -0.2, 0.2], 0.1), None),
            None
        );
    }

    #[test]
    fn outlines_clip_segments() {
        let square = Shape::Box {
            size: [2.0, 2.0, 1.0],
        };
        let v = Vector2::new;
        assert_eq!(
            outline_interval(&square, v(-2.0, 0.0), v(2.0, 0.0)),
            Some((0.25, 0.75))
        );
        assert_eq!(outline_interval(&square, v(-2.0, 1.5), v(2.0, 1.5)), None);
        assert_eq!(
            outline_interval(&square, v(0.5, 0.5), v(0.5, 0.5)),
            Some((0.0, 1.0))
        );
        let disc = Shape::Cylinder {
            radius: 1.0,
            length: 1.0,
        };
        let (a, b) = outline_interval(&disc, v(-2.0, 0.0), v(2.0, 0.0)).unwrap();
        assert!((a - 0.25).abs() < 1e-12 && (b - 0.75).abs() < 1e-12);
        assert_eq!(outline_interval(&disc, v(-2.0, 1.5), v(2.0, 1.5)), None);
        assert_eq!(outline_interval(&disc, v(3.0, 0.0), v(5.0, 0.0)), None);
    }
}
