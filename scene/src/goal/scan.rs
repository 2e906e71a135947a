//! The `scan` goal: an object carried over a row of scanners in a straight line, in the row's
//! order, judged on the path the object took.

use super::find;
use crate::paths::{ObjectPaths, PathSample};
use crate::world::{Object, World};
use akl_tsr::nalgebra::{Matrix3, SymmetricEigen, Vector3};
use akl_tsr::Pose;

/// Spacing (metres) at which a path is filled in between its samples, so that passing over a
/// scanner is seen whatever rate the path was sampled at: a fifth of the 5 mm straightness
/// tolerance, and far below any scanner's size.
const FILL_STEP: f64 = 1e-3;

/// The parameters of a `scan` goal.
pub(super) struct Scan<'a> {
    pub object: &'a str,
    pub scanners: &'a [String],
    pub height: [f64; 2],
    pub max_deviation: f64,
    pub max_angle: f64,
}

/// Checks the values of a `scan` goal; the error names the field.
pub(super) fn validate(
    object: &str,
    scanners: &[String],
    [lo, hi]: [f64; 2],
    max_deviation: f64,
    max_angle: f64,
) -> Result<(), (String, String)> {
    let field = |f: &str, p: String| Err((f.to_string(), p));
    if scanners.is_empty() {
        return field("scanners", "lists no scanner".into());
    }
    for (i, s) in scanners.iter().enumerate() {
        if s == object {
            return field("scanners", format!("`{s}` cannot pass over itself"));
        }
        if scanners[..i].contains(s) {
            return field("scanners", format!("names `{s}` twice"));
        }
    }
    if !lo.is_finite() || !hi.is_finite() || lo < 0.0 || lo >= hi {
        return field(
            "height",
            format!("must be finite with 0 <= min < max, got [{lo}, {hi}]"),
        );
    }
    if !max_deviation.is_finite() || max_deviation <= 0.0 {
        return field(
            "max_deviation",
            format!("must be finite and > 0, got {max_deviation}"),
        );
    }
    if !max_angle.is_finite() || max_angle <= 0.0 || max_angle > std::f64::consts::FRAC_PI_2 {
        return field(
            "max_angle",
            format!("must be in (0, π/2] radians, got {max_angle}"),
        );
    }
    Ok(())
}

/// What the path showed about one scanner.
#[derive(Clone, Copy)]
struct Seen {
    /// Whether the object passed entirely over it at scan height.
    crossed: bool,
    /// The least the object's centre was outside the scanner's outline (metres).
    centre_closest: f64,
    /// While its centre was over the scanner, the least its outline reached beyond the
    /// scanner's (metres; <= 0: entirely over it).
    closest: f64,
    /// While entirely over it, the height above its top nearest to the scan band.
    height_over: Option<f64>,
}

/// Evaluates a `scan` goal on the object's path in `paths`, with the scanners where `end`
/// has them (furniture does not move during an execution).
pub(super) fn evaluate(end: &World, paths: &ObjectPaths, scan: &Scan) -> Result<String, String> {
    let object = scan.object;
    let part = find(end, object)?;
    let scanners = scan
        .scanners
        .iter()
        .map(|s| find(end, s))
        .collect::<Result<Vec<&Object>, String>>()?;
    let path = filled(paths.path(object));
    if path.is_empty() {
        return Err(format!("no path of {object} was recorded"));
    }
    let [lo, hi] = scan.height;
    let distance_to_band = |h: f64| (lo - h).max(h - hi).max(0.0);
    let mut seen = vec![
        Seen {
            crossed: false,
            centre_closest: f64::INFINITY,
            closest: f64::INFINITY,
            height_over: None,
        };
        scanners.len()
    ];
    let mut crossings: Vec<(usize, usize)> = Vec::new();
    for (i, pose) in path.iter().enumerate() {
        // The outline's corners are only needed while the centre is over a scanner (the
        // largest corner excess is never below the centre's, the excess being convex).
        let mut corners = None;
        for (k, (s, seen)) in scanners.iter().zip(seen.iter_mut()).enumerate() {
            let centre = s
                .shape
                .outline_excess_of(&s.pose, &[pose.translation.vector.into()]);
            seen.centre_closest = seen.centre_closest.min(centre);
            if centre > 0.0 {
                continue;
            }
            let corners = corners.get_or_insert_with(|| part.shape.corners(pose));
            let beyond = s.shape.outline_excess_of(&s.pose, corners.as_slice());
            seen.closest = seen.closest.min(beyond);
            if beyond > 0.0 {
                continue;
            }
            let h = part.shape.bottom(pose) - s.shape.top(&s.pose);
            if seen
                .height_over
                .is_none_or(|best| distance_to_band(h) < distance_to_band(best))
            {
                seen.height_over = Some(h);
            }
            if (lo..=hi).contains(&h) {
                seen.crossed = true;
                crossings.push((i, k));
            }
        }
    }
    for (s, seen) in scanners.iter().zip(&seen) {
        if seen.crossed {
            continue;
        }
        return Err(match seen.height_over {
            Some(h) => format!(
                "{object} passed over {} only {h:.3} m above it (scan height {lo}–{hi} m)",
                s.name
            ),
            None if seen.closest.is_finite() => format!(
                "{object} never passed entirely over {}: at best it reached {:.1} mm beyond its outline",
                s.name,
                seen.closest * 1e3
            ),
            None => format!(
                "{object} never passed over {}: its centre stayed at least {:.1} mm outside its outline",
                s.name,
                seen.centre_closest * 1e3
            ),
        });
    }
    // Every shortest stretch of the path over the whole row is a candidate pass; the goal
    // holds if one of them is straight and runs along the row. Taking the shortest stretches
    // keeps a free motion that also happens over a scanner at scan height, before or after
    // the pass, out of the pass.
    let mut straightest: Option<f64> = None;
    let mut best_aligned: Option<f64> = None;
    for (first, last) in sweeps(&crossings, scanners.len()) {
        let over_row: Vec<Vector3<f64>> = path[first..=last]
            .iter()
            .map(|p| p.translation.vector)
            .collect();
        let travel = over_row[over_row.len() - 1] - over_row[0];
        let (deviation, direction) = fit_line(&over_row);
        let heading = if direction.dot(&travel) < 0.0 {
            -direction
        } else {
            direction
        };
        let angle = angle_to_row(&heading, &scanners);
        let length = travel.norm();
        if deviation <= scan.max_deviation && angle <= scan.max_angle {
            return Ok(format!(
                "passed over {} scanners; path over the row {:.1} mm from straight over {length:.3} m, {:.1}° off the row",
                scanners.len(),
                deviation * 1e3,
                angle.to_degrees()
            ));
        }
        if straightest.is_none_or(|d| deviation < d) {
            straightest = Some(deviation);
        }
        if deviation <= scan.max_deviation && best_aligned.is_none_or(|a| angle < a) {
            best_aligned = Some(angle);
        }
    }
    Err(match (best_aligned, straightest) {
        (Some(angle), _) if angle > std::f64::consts::FRAC_PI_2 => format!(
            "{object} crossed the row from its last scanner towards its first, {:.1}° from the \
             row's direction (the scanners are crossed in the order the goal lists them)",
            angle.to_degrees()
        ),
        (Some(angle), _) => format!(
            "{object}'s path over the row runs {:.1}° off the row's direction (at most {:.1}° allowed)",
            angle.to_degrees(),
            scan.max_angle.to_degrees()
        ),
        (None, Some(deviation)) => format!(
            "{object}'s path over the row leaves a straight line by {:.1} mm (at most {:.1} mm allowed)",
            deviation * 1e3,
            scan.max_deviation * 1e3
        ),
        (None, None) => format!("{object} passed over no scanner"),
    })
}

/// The shortest stretches of a path that cross every one of `scanners` scanners, as (first,
/// last) sample indices, from `crossings`: the (sample, scanner) pairs, in path order, at which
/// the object was entirely over a scanner at scan height. A stretch is shortest when dropping
/// its first or its last crossing would leave a scanner uncrossed.
fn sweeps(crossings: &[(usize, usize)], scanners: usize) -> Vec<(usize, usize)> {
    let mut count = vec![0usize; scanners];
    let mut covered = 0;
    let mut start = 0;
    let mut out = Vec::new();
    for &(sample, scanner) in crossings {
        if count[scanner] == 0 {
            covered += 1;
        }
        count[scanner] += 1;
        if covered < scanners {
            continue;
        }
        while count[crossings[start].1] > 1 {
            count[crossings[start].1] -= 1;
            start += 1;
        }
        if count[scanner] == 1 {
            out.push((crossings[start].0, sample));
        }
    }
    out
}

/// The path's poses with poses interpolated between samples at most [`FILL_STEP`] apart.
fn filled(samples: &[PathSample]) -> Vec<Pose> {
    let mut poses = Vec::with_capacity(samples.len());
    if let Some(first) = samples.first() {
        poses.push(first.pose);
    }
    for pair in samples.windows(2) {
        let (a, b) = (&pair[0].pose, &pair[1].pose);
        let length = (b.translation.vector - a.translation.vector).norm();
        let steps = (length / FILL_STEP).ceil().max(1.0) as usize;
        for k in 1..=steps {
            let s = k as f64 / steps as f64;
            let mut pose = *b;
            pose.translation.vector = a.translation.vector.lerp(&b.translation.vector, s);
            pose.rotation = a
                .rotation
                .try_slerp(&b.rotation, s, 1e-9)
                .unwrap_or(if s < 0.5 { a.rotation } else { b.rotation });
            poses.push(pose);
        }
    }
    poses
}

/// The largest distance of `points` from their least-squares line (the line through their
/// centroid along their principal direction), and that direction. The distance is an upper
/// bound on how far they are from the best straight line; zero for fewer than two points.
fn fit_line(points: &[Vector3<f64>]) -> (f64, Vector3<f64>) {
    if points.len() < 2 {
        return (0.0, Vector3::zeros());
    }
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let scatter: Matrix3<f64> = points
        .iter()
        .map(|p| (p - centroid) * (p - centroid).transpose())
        .sum();
    let eigen = SymmetricEigen::new(scatter);
    let direction: Vector3<f64> = eigen.eigenvectors.column(eigen.eigenvalues.imax()).into();
    let deviation = points
        .iter()
        .map(|p| {
            let d = p - centroid;
            (d - direction * d.dot(&direction)).norm()
        })
        .fold(0.0, f64::max);
    (deviation, direction)
}

/// The angle (radians, 0 to π) between the heading `direction` and the row's direction (from
/// the first scanner's centre to the last's), both seen from above: a pass in the listed order
/// runs near 0, one in the reverse order near π. 0 for a row of one scanner.
fn angle_to_row(direction: &Vector3<f64>, scanners: &[&Object]) -> f64 {
    let (Some(first), Some(last)) = (scanners.first(), scanners.last()) else {
        return 0.0;
    };
    let flat = |v: Vector3<f64>| Vector3::new(v.x, v.y, 0.0).try_normalize(1e-12);
    let row = flat(last.pose.translation.vector - first.pose.translation.vector);
    match (row, flat(*direction)) {
        (Some(row), Some(path)) => row.dot(&path).clamp(-1.0, 1.0).acos(),
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;
    use crate::Task;
    use akl_tsr::pose::pose_from_xyz;

    fn task() -> Task {
        builtin::task("inspection").unwrap().unwrap()
    }

    /// A path of the part through `points` (world positions of its centre), upright, sampled
    /// every `step` metres along straight pieces between them.
    fn path_through(points: &[[f64; 3]], step: f64) -> ObjectPaths {
        let mut paths = ObjectPaths::new();
        let mut t = 0.0;
        for pair in points.windows(2) {
            let (a, b) = (Vector3::from(pair[0]), Vector3::from(pair[1]));
            let n = ((b - a).norm() / step).ceil().max(1.0) as usize;
            for k in 0..n {
                let p = a.lerp(&b, k as f64 / n as f64);
                paths.push("part", t, pose_from_xyz([p.x, p.y, p.z]));
                t += 0.01;
            }
        }
        let last = points[points.len() - 1];
        paths.push("part", t, pose_from_xyz(last));
        paths
    }

    fn scan_goal(t: &Task) -> &crate::Goal {
        t.goals
            .iter()
            .find(|g| g.kind() == "scan")
            .expect("inspection has a scan goal")
    }

    /// The part's centre 5 cm above the scanners' tops (its bottom at 0.15 m), along x = 0.55.
    const START: [f64; 3] = [0.45, 0.32, 0.19];
    const END: [f64; 3] = [0.45, -0.36, 0.19];

    #[test]
    fn a_straight_pass_at_scan_height_holds_at_any_sampling_rate() {
        let t = task();
        for step in [0.001, 0.03, 0.2] {
            let paths = path_through(&[START, [0.55, 0.18, 0.2], [0.55, -0.18, 0.2], END], step);
            let c = scan_goal(&t).check(&t.world, &paths, &t.world);
            assert!(c.holds, "step {step}: {}", c.detail);
        }
    }

    #[test]
    fn skipping_the_scanners_fails() {
        let t = task();
        let paths = path_through(&[START, [0.4, 0.0, 0.25], END], 0.005);
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(
            !c.holds
                && c.detail
                    .contains("never passed over scanner_1: its centre stayed"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn passing_too_high_fails_for_its_height() {
        let t = task();
        let paths = path_through(
            &[START, [0.55, 0.18, 0.35], [0.55, -0.18, 0.35], END],
            0.005,
        );
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(
            !c.holds && c.detail.contains("only 0.200 m above"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn passing_beside_a_scanner_fails() {
        let t = task();
        // 3 cm off the row's centre line: the 5 cm part sticks out of the 10 cm scanners.
        let paths = path_through(&[START, [0.58, 0.18, 0.2], [0.58, -0.18, 0.2], END], 0.005);
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(
            !c.holds && c.detail.contains("5.0 mm beyond"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn a_bent_path_over_the_row_fails_for_its_deviation() {
        let t = task();
        let row = |via: &[[f64; 3]]| {
            let mut points = vec![START, [0.55, 0.18, 0.2]];
            points.extend_from_slice(via);
            points.extend_from_slice(&[[0.55, -0.18, 0.2], END]);
            path_through(&points, 0.005)
        };
        // Entirely over every scanner at scan height, but zigzagging 1.2 cm to either side.
        let weaving = row(&[[0.562, 0.1, 0.2], [0.538, 0.0, 0.2], [0.562, -0.1, 0.2]]);
        // Dipping 3 cm over the middle scanner (still 2 cm above it).
        let dipping = row(&[[0.55, 0.0, 0.17]]);
        for paths in [weaving, dipping] {
            let c = scan_goal(&t).check(&t.world, &paths, &t.world);
            assert!(
                !c.holds && c.detail.contains("leaves a straight line"),
                "{}",
                c.detail
            );
        }
        // A 2 mm kink is within the 5 mm tolerance.
        let kinked = row(&[[0.552, 0.0, 0.2]]);
        let c = scan_goal(&t).check(&t.world, &kinked, &t.world);
        assert!(c.holds, "{}", c.detail);
    }

    #[test]
    fn a_free_motion_over_a_scanner_before_the_pass_is_not_part_of_it() {
        let t = task();
        // Over scanner_3 at scan height first, away, then one straight pass over the row.
        let paths = path_through(
            &[
                START,
                [0.55, -0.1, 0.2],
                [0.4, 0.1, 0.3],
                [0.55, 0.18, 0.2],
                [0.55, -0.18, 0.2],
                END,
            ],
            0.005,
        );
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(c.holds, "{}", c.detail);
        // Without the straight pass, the scanners crossed one by one do not make a scan.
        let paths = path_through(
            &[
                START,
                [0.55, 0.1, 0.2],
                [0.4, 0.0, 0.3],
                [0.55, 0.0, 0.2],
                [0.4, -0.1, 0.3],
                [0.55, -0.1, 0.2],
                END,
            ],
            0.005,
        );
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(
            !c.holds && c.detail.contains("leaves a straight line"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn the_shortest_stretches_over_every_scanner_are_found() {
        let crossings = [(0, 0), (1, 0), (5, 1), (9, 2), (10, 2), (20, 0)];
        assert_eq!(sweeps(&crossings, 3), vec![(1, 9), (5, 20)]);
        assert_eq!(sweeps(&crossings[..3], 3), vec![]);
        assert_eq!(sweeps(&[(4, 0), (7, 0)], 1), vec![(4, 4), (7, 7)]);
    }

    #[test]
    fn a_straight_pass_slanted_across_the_row_fails_for_its_angle() {
        let t = task();
        let pass = |from: [f64; 3], to: [f64; 3]| path_through(&[START, from, to, END], 0.005);
        // Entirely over every scanner, straight, but 8.5° across the row.
        let slanted = pass([0.58, 0.2, 0.2], [0.52, -0.2, 0.2]);
        let c = scan_goal(&t).check(&t.world, &slanted, &t.world);
        assert!(
            !c.holds && c.detail.contains("off the row's direction"),
            "{}",
            c.detail
        );
        // 1.7° across it is along the row.
        let nearly = pass([0.556, 0.2, 0.2], [0.544, -0.2, 0.2]);
        let c = scan_goal(&t).check(&t.world, &nearly, &t.world);
        assert!(c.holds, "{}", c.detail);
    }

    #[test]
    fn a_pass_in_the_reverse_order_fails_for_its_direction() {
        let t = task();
        // From scanner_3 to scanner_1, straight and along the row.
        let paths = path_through(&[END, [0.55, -0.18, 0.2], [0.55, 0.18, 0.2], START], 0.005);
        let c = scan_goal(&t).check(&t.world, &paths, &t.world);
        assert!(
            !c.holds && c.detail.contains("from its last scanner towards its first"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn no_recorded_path_fails() {
        let t = task();
        let c = scan_goal(&t).check(&t.world, &ObjectPaths::new(), &t.world);
        assert!(!c.holds && c.detail.contains("no path"), "{}", c.detail);
    }

    #[test]
    fn scan_values_are_checked_by_field() {
        let s = ["scanner_1".to_string()];
        assert_eq!(
            validate("part", &s, [0.05, 0.02], 0.005, 0.05)
                .unwrap_err()
                .0,
            "height"
        );
        assert_eq!(
            validate("part", &s, [0.0, 0.02], 0.0, 0.05).unwrap_err().0,
            "max_deviation"
        );
        assert_eq!(
            validate("part", &s, [0.0, 0.02], 0.005, 2.0).unwrap_err().0,
            "max_angle"
        );
        assert_eq!(
            validate("part", &[], [0.0, 0.02], 0.005, 0.05)
                .unwrap_err()
                .0,
            "scanners"
        );
        let twice = ["scanner_1".to_string(), "scanner_1".to_string()];
        assert!(validate("part", &twice, [0.0, 0.02], 0.005, 0.05)
            .unwrap_err()
            .1
            .contains("twice"));
    }

    #[test]
    fn a_straight_line_has_no_deviation_and_a_kink_has_its_own() {
        let line: Vec<Vector3<f64>> = (0..10)
            .map(|i| Vector3::new(0.1 * i as f64, 0.05 * i as f64, 0.0))
            .collect();
        assert!(fit_line(&line).0 < 1e-12);
        let kink = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.5, 0.01, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
        ];
        let d = fit_line(&kink).0;
        assert!(d > 0.005 && d < 0.01, "{d}");
    }
}
