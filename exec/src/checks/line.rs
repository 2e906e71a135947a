//! Line check: over each `move_in_line` segment the simulated TCP stays within the tolerance
//! of the straight line between where it started and where it ended.

use crate::report::Cause;
use crate::report::{Failure, LineCheck};
use crate::simulate::observations::LinePath;
use akl_planner::distance_to_segment;

/// One check per line; a failure for each that strayed further than `tolerance` (metres), at
/// the first step the TCP was beyond it.
pub(crate) fn check(lines: &[LinePath], tolerance: f64) -> (Vec<LineCheck>, Vec<Failure>) {
    let mut checks = Vec::with_capacity(lines.len());
    let mut failures = Vec::new();
    for line in lines {
        let (Some((_, from)), Some((_, to))) = (line.points.first(), line.points.last()) else {
            continue;
        };
        let distances: Vec<(f64, f64)> = line
            .points
            .iter()
            .map(|(t, p)| (*t, distance_to_segment(p, from, to)))
            .collect();
        let deviation = distances.iter().map(|(_, d)| *d).fold(0.0, f64::max);
        let within = deviation <= tolerance;
        if !within {
            let left = distances
                .iter()
                .find(|(_, d)| *d > tolerance)
                .map_or(line.start, |(t, _)| *t);
            failures.push(Failure::new(
                Cause::LineDeviation,
                format!(
                    "line to keyframe {}: the simulated TCP strays {:.1} mm from the line (tolerance {:.1} mm)",
                    line.keyframe,
                    deviation * 1e3,
                    tolerance * 1e3
                ),
            ).at(line.keyframe).at_time(left));
        }
        checks.push(LineCheck {
            keyframe: line.keyframe,
            start: line.start,
            end: line.end,
            from: [from.x, from.y, from.z],
            to: [to.x, to.y, to.z],
            deviation,
            within,
        });
    }
    (checks, failures)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::nalgebra::Vector3;

    #[test]
    fn a_line_check_reports_the_largest_deviation_of_the_path() {
        let path = LinePath {
            keyframe: 2,
            start: 0.0,
            end: 1.0,
            points: vec![
                (0.0, Vector3::new(0.0, 0.0, 0.0)),
                (0.2, Vector3::new(0.5, 0.004, 0.0)),
                (0.6, Vector3::new(0.7, 0.0, 0.006)),
                (1.0, Vector3::new(1.0, 0.0, 0.0)),
            ],
        };
        let (checks, failures) = check(std::slice::from_ref(&path), 0.005);
        assert!((checks[0].deviation - 0.006).abs() < 1e-12 && !checks[0].within);
        assert_eq!(failures[0].cause, Cause::LineDeviation);
        assert_eq!(failures[0].t, Some(0.6), "when it first left the tolerance");
        let (_, failures) = check(std::slice::from_ref(&path), 0.003);
        assert_eq!(failures[0].t, Some(0.2));
        let (checks, failures) = check(&[path], 0.007);
        assert!(checks[0].within && failures.is_empty());
    }
}
