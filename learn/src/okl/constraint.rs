//! Algorithm 1, lines 10–12: denoise the fitting errors, threshold them, and take the
//! boundaries of the constrained stretch as constraint keyframes.

use super::line::{fit_line, fitting_errors, true_line};
use super::segment::Segment;
use crate::tvd;
use akl_tsr::nalgebra::Vector3;
use std::ops::RangeInclusive;

/// Tuning of constraint extraction (see [`super::OklParams`] for the defaults and why).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ConstraintParams {
    /// D_F, the online detector's distance filter step (metres).
    pub filter_distance: f64,
    /// How far a detected region overshoots its line (metres): cut off its end.
    pub overshoot: f64,
    /// How far the line runs before the detected region at least (metres): fit from there.
    pub lead: f64,
    /// λ of the total variation denoising of the fitting error (metres × frames).
    pub tvd_lambda: f64,
    /// ε added to the largest smoothed error on the true line to get σ (metres).
    pub epsilon: f64,
}

/// Line 11, `getThreshold`: σ = max(e_l) + ε, the largest smoothed error over the true-line
/// frames `line` (indices into `smoothed`) plus `epsilon`.
pub(crate) fn threshold(smoothed: &[f64], line: &RangeInclusive<usize>, epsilon: f64) -> f64 {
    smoothed[line.clone()]
        .iter()
        .fold(f64::NEG_INFINITY, |m, &e| m.max(e))
        + epsilon
}

/// Line 12, `ConstraintKF`: the boundary indices of the constrained stretch — the maximal run
/// of indices around the true line `line` whose smoothed error stays within `sigma`.
pub(crate) fn constraint_boundaries(
    smoothed: &[f64],
    line: &RangeInclusive<usize>,
    sigma: f64,
) -> (usize, usize) {
    let mut a = *line.start();
    while a > 0 && smoothed[a - 1] <= sigma {
        a -= 1;
    }
    let mut b = *line.end();
    while b + 1 < smoothed.len() && smoothed[b + 1] <= sigma {
        b += 1;
    }
    (a, b)
}

/// Lines 7–12 for one constrained region of one segment: the frames where the true
/// constrained motion starts and ends, or `None` when the region holds no line to fit or the
/// line found is a single frame.
///
/// A region that starts at its segment's first frame holds no line when its true-line part
/// spans less than half the filter distance: that is the tail of a detection that started in
/// the previous segment (a recording made by a detector that was not reset at gripper
/// commands keeps its state for its overshoot past a line ending at one, so the clipped tail
/// in the next segment is about that long and its true-line part is a point; a real detection
/// needs at least `2·D_F` of line before it switches on). Any other region is a real
/// detection, however late: its fit starts [`ConstraintParams::lead`] before it.
pub(crate) fn learn_constraint(
    positions: &[Vector3<f64>],
    segment: &Segment,
    region: &RangeInclusive<usize>,
    params: &ConstraintParams,
) -> Option<(usize, usize)> {
    // A region that reaches the end of its segment was cut there by the gripper command, not
    // ended by the detector switching off: it has no overshoot to remove.
    let overshoot = if *region.end() == segment.end {
        0.0
    } else {
        params.overshoot
    };
    let l = true_line(positions, region, overshoot)?;
    let span = (positions[*l.end()] - positions[*l.start()]).norm();
    if *region.start() == segment.start && span < 0.5 * params.filter_distance {
        return None;
    }
    let l = lead_in(positions, segment.start, &l, params.lead);
    let line = fit_line(&positions[l.clone()])?;
    let errors = fitting_errors(positions, segment.frames(), &line);
    let smoothed = tvd::denoise(&errors, params.tvd_lambda);
    let local = (*l.start() - segment.start)..=(*l.end() - segment.start);
    let sigma = threshold(&smoothed, &local, params.epsilon);
    let (a, b) = constraint_boundaries(&smoothed, &local, sigma);
    let (a, b) = (segment.start + a, segment.start + b);
    ((positions[b] - positions[a]).norm() > 0.0 && b > a).then_some((a, b))
}

/// `line` started earlier, at the first frame (not before `first`) within `lead` metres of its
/// start, walking back.
fn lead_in(
    positions: &[Vector3<f64>],
    first: usize,
    line: &RangeInclusive<usize>,
    lead: f64,
) -> RangeInclusive<usize> {
    let origin = positions[*line.start()];
    let mut a = *line.start();
    while a > first && (positions[a - 1] - origin).norm() <= lead {
        a -= 1;
    }
    a..=*line.end()
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::Gripper;

    #[test]
    fn threshold_is_the_largest_line_error_plus_epsilon() {
        let s = [5.0, 1.0, 2.0, 1.5, 9.0];
        assert_eq!(threshold(&s, &(1..=3), 0.5), 2.5);
    }

    #[test]
    fn boundaries_grow_the_line_while_under_sigma() {
        let s = [3.0, 1.0, 0.5, 0.2, 0.2, 0.9, 1.2, 0.1];
        assert_eq!(constraint_boundaries(&s, &(3..=4), 1.0), (1, 5));
        assert_eq!(constraint_boundaries(&s, &(3..=4), 0.3), (3, 4));
        assert_eq!(constraint_boundaries(&s, &(3..=4), 10.0), (0, 7));
    }

    #[test]
    fn recovers_a_line_between_two_curves() {
        // An arc, a straight line from frame 100 to 200, another arc; the detector region
        // starts late (frame 130) and ends 5 cm late.
        let mut p = Vec::new();
        for i in 0..100 {
            let a = std::f64::consts::FRAC_PI_2 * (1.0 - i as f64 / 100.0);
            p.push(Vector3::new(-0.1 + 0.1 * a.cos(), 0.1 * a.sin() - 0.1, 0.3));
        }
        for i in 0..=100 {
            p.push(Vector3::new(i as f64 * 0.003, 0.0, 0.3));
        }
        for i in 1..100 {
            let a = std::f64::consts::FRAC_PI_2 * i as f64 / 100.0;
            p.push(Vector3::new(
                0.3 + 0.1 * a.sin(),
                0.1 * (1.0 - a.cos()),
                0.3,
            ));
        }
        let seg = Segment {
            start: 0,
            end: p.len() - 1,
            gripper: Gripper::Closed,
        };
        let end = (200..p.len())
            .find(|&k| (p[k] - p[200]).norm() >= 0.05)
            .unwrap();
        let params = ConstraintParams {
            filter_distance: 0.05,
            overshoot: 0.05,
            lead: 0.1,
            tvd_lambda: 0.002,
            epsilon: 0.001,
        };
        let (a, b) = learn_constraint(&p, &seg, &(130..=end), &params).unwrap();
        assert!((p[a] - p[100]).norm() < 0.02, "start {a}");
        assert!((p[b] - p[200]).norm() < 0.02, "end {b}");
    }
}
