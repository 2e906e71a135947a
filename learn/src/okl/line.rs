//! Algorithm 1, lines 7–9: the true-line part of a detected region, the least-squares 3-D line
//! through it, and every frame's distance to that line.

use akl_tsr::nalgebra::{Matrix3, SymmetricEigen, Vector3};
use std::ops::RangeInclusive;

/// A straight line in space: a point on it and a unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// The centroid of the points the line was fitted to.
    pub point: Vector3<f64>,
    /// Unit direction.
    pub direction: Vector3<f64>,
}

impl Line {
    /// Perpendicular distance of `p` from the (infinite) line, in the unit of the positions.
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        let v = p - self.point;
        (v - self.direction * v.dot(&self.direction)).norm()
    }
}

/// Line 7, `getTrueLine`: the region without its last stretch of length `overshoot`.
///
/// The online detector switches off only once the distance filter has collected frames past
/// the end of the true line, so the region overshoots the line (thesis §3.3.2: by D_F for a
/// detector that switches on one filtered point): the true-line part is frames `start..=m`,
/// `m` the last frame at least `overshoot` from the region's last frame. `None` when no frame
/// is that far (the region is too short to hold a reliable line).
pub(crate) fn true_line(
    positions: &[Vector3<f64>],
    region: &RangeInclusive<usize>,
    overshoot: f64,
) -> Option<RangeInclusive<usize>> {
    let (a, b) = (*region.start(), *region.end());
    let last = positions[b];
    (a..=b)
        .rev()
        .find(|&m| (positions[m] - last).norm() >= overshoot)
        .map(|m| a..=m)
}

/// Line 8, `FitLineModel`: the least-squares line through `points` (total least squares: the
/// line through the centroid along the principal axis of the scatter, which minimizes the sum
/// of squared perpendicular distances and, unlike fitting two coordinates as functions of the
/// third, does not depend on how the line is oriented). `None` for fewer than two points or
/// points that all coincide (no direction).
pub fn fit_line(points: &[Vector3<f64>]) -> Option<Line> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let centroid = points.iter().sum::<Vector3<f64>>() / n;
    let mut scatter = Matrix3::zeros();
    for p in points {
        let d = p - centroid;
        scatter += d * d.transpose();
    }
    if scatter.trace() <= f64::EPSILON * (1.0 + centroid.norm_squared()) * n {
        return None;
    }
    let eig = SymmetricEigen::new(scatter);
    let i = eig.eigenvalues.imax();
    let direction = eig.eigenvectors.column(i).normalize();
    direction.iter().all(|v| v.is_finite()).then_some(Line {
        point: centroid,
        direction,
    })
}

/// Line 9, `FittingError`: the distance of every frame in `frames` from `line`.
pub fn fitting_errors(
    positions: &[Vector3<f64>],
    frames: RangeInclusive<usize>,
    line: &Line,
) -> Vec<f64> {
    positions[frames].iter().map(|p| line.distance(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    #[test]
    fn true_line_cuts_the_filter_distance_off_the_end() {
        let p: Vec<_> = (0..=20).map(|i| v(i as f64 * 0.01, 0.0, 0.0)).collect();
        // Frames 5..=20 span 0.05..0.20; the last frame 0.05 m or more before 0.20 is 15.
        assert_eq!(true_line(&p, &(5..=20), 0.05), Some(5..=15));
        assert_eq!(true_line(&p, &(5..=8), 0.05), None);
    }

    #[test]
    fn fits_an_exact_line_in_any_orientation() {
        let d = v(1.0, -2.0, 0.5).normalize();
        let pts: Vec<_> = (0..10)
            .map(|i| v(0.1, 0.2, 0.3) + d * i as f64 * 0.02)
            .collect();
        let line = fit_line(&pts).unwrap();
        assert!(line.direction.dot(&d).abs() > 1.0 - 1e-12);
        for p in &pts {
            assert!(line.distance(p) < 1e-12);
        }
        assert!(
            (line.distance(&(pts[3] + v(0.0, 0.0, 1.0).cross(&d).normalize() * 0.01)) - 0.01).abs()
                < 1e-9
        );
    }

    #[test]
    fn degenerate_point_sets_have_no_line() {
        assert!(fit_line(&[]).is_none());
        assert!(fit_line(&[v(1.0, 2.0, 3.0)]).is_none());
        assert!(fit_line(&[v(1.0, 2.0, 3.0); 5]).is_none());
    }

    #[test]
    fn fitting_errors_cover_the_frames() {
        let p = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.5, 0.0)];
        let line = Line {
            point: v(0.0, 0.0, 0.0),
            direction: v(1.0, 0.0, 0.0),
        };
        assert_eq!(fitting_errors(&p, 1..=2, &line), vec![0.0, 0.5]);
    }

    proptest! {
        #[test]
        fn fit_minimizes_squared_distances(
            pts in prop::collection::vec(prop::array::uniform3(-1.0..1.0f64), 3..30),
            tilt in prop::array::uniform3(-0.1..0.1f64),
        ) {
            let pts: Vec<_> = pts.iter().map(|a| v(a[0], a[1], a[2])).collect();
            if let Some(line) = fit_line(&pts) {
                let cost = |l: &Line| pts.iter().map(|p| l.distance(p).powi(2)).sum::<f64>();
                let other = Line {
                    point: line.point + v(tilt[0], tilt[1], tilt[2]) * 0.1,
                    direction: (line.direction + v(tilt[0], tilt[1], tilt[2])).normalize(),
                };
                prop_assert!(cost(&line) <= cost(&other) + 1e-9);
            }
        }
    }
}
