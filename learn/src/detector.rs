//! The online constraint detector of thesis §3.3.1.1 (eqs. 3.2–3.5).
//!
//! End-effector positions are thinned by a distance filter (D_F), each new filtered point gives
//! the perpendicular distance d_i of p_{j+2} from the line p_j→p_{j+1} (eq. 3.2), a per-user
//! logistic regression turns d_i into the probability that the constraint state switches
//! (eq. 3.3), and an energy tank decides when it does (eqs. 3.4–3.5). One [`Detector::push`]
//! per recorded frame: constant time, no allocation.
//!
//! Two rules the thesis implies but does not spell out:
//! - **A rejected line stays rejected.** After "no" ([`Detector::reject`]) the state reads
//!   unconstrained at once, but the tank keeps following the rejected line as if it were still
//!   constrained: only once the motion has left that line (the tank would have switched the
//!   state back to unconstrained) can a new line switch it on and raise a new question. Without
//!   this, a hand that keeps moving straight refills the empty tank and the same line is asked
//!   about again a few centimetres later.
//! - **A detection ends at a gripper command.** [`Detector::reset`] forgets the filtered points,
//!   the tank and the state, so a line answered before a grasp or release never carries into
//!   the next interaction segment: motion there is asked about afresh.

use k::nalgebra::Vector3;

use crate::calibration::Calibration;
use crate::line_error::line_error;

/// What a frame did to the detector's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Switch {
    /// The new state: true = constrained (moving in a line).
    pub constrained: bool,
    /// The line distance error d_i (m) of the filtered point that tipped the tank.
    pub error: f64,
    /// Where the detected line starts: the filtered point two steps before the current one.
    pub line_start: Vector3<f64>,
}

/// The streaming detector: feed it end-effector positions in order.
#[derive(Debug, Clone)]
pub struct Detector {
    calibration: Calibration,
    /// The last three filtered points, oldest first; `count` of them are valid.
    filtered: [Vector3<f64>; 3],
    count: usize,
    tank: f64,
    constrained: bool,
    /// The teacher rejected the line under way: the state reads unconstrained while the tank
    /// waits for the motion to leave it.
    rejected: bool,
    line_start: Vector3<f64>,
}

impl Detector {
    /// A detector in the unconstrained state with an empty tank.
    pub fn new(calibration: Calibration) -> Self {
        Detector {
            calibration,
            filtered: [Vector3::zeros(); 3],
            count: 0,
            tank: 0.0,
            constrained: false,
            rejected: false,
            line_start: Vector3::zeros(),
        }
    }

    /// The calibration in use.
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// The current state Y_c (true = constrained).
    pub fn constrained(&self) -> bool {
        self.constrained
    }

    /// The current tank energy T_i.
    pub fn tank(&self) -> f64 {
        self.tank
    }

    /// Takes one end-effector position; returns the switch it caused, if any.
    ///
    /// The distance filter keeps a sample once it is at least D_F from the last kept one (the
    /// first such sample, not an interpolated point, so every filtered point was really visited).
    pub fn push(&mut self, p: Vector3<f64>) -> Option<Switch> {
        if self.count == 0 {
            self.filtered[0] = p;
            self.count = 1;
            return None;
        }
        let last = self.filtered[self.count - 1];
        if (p - last).norm() < self.calibration.filter_distance {
            return None;
        }
        if self.count < 3 {
            self.filtered[self.count] = p;
            self.count += 1;
        } else {
            self.filtered = [self.filtered[1], self.filtered[2], p];
        }
        if self.count < 3 {
            return None;
        }
        let d = line_error(&self.filtered[0], &self.filtered[1], &self.filtered[2]);
        self.step(d).then_some(Switch {
            constrained: self.constrained,
            error: d,
            line_start: self.line_start,
        })
    }

    /// One tank update with distance error `d` (eqs. 3.3–3.5); true when the state switched.
    ///
    /// The tank is kept at or above zero: the thesis does not bound it, but an unbounded
    /// negative tank would let a long stretch of one state delay the next switch arbitrarily.
    /// While a rejected line is under way the tank runs as in the constrained state, and
    /// filling it ends the rejection instead of switching the (already unconstrained) state.
    fn step(&mut self, d: f64) -> bool {
        let p_unconstrained = self.calibration.probability_unconstrained(d);
        let p_switch = if self.constrained || self.rejected {
            p_unconstrained
        } else {
            1.0 - p_unconstrained
        };
        self.tank = (self.tank + p_switch * p_switch - self.calibration.tank_dissipation).max(0.0);
        if self.tank < self.calibration.tank_threshold {
            return false;
        }
        self.tank = 0.0;
        if self.rejected {
            self.rejected = false;
            return false;
        }
        self.constrained = !self.constrained;
        if self.constrained {
            self.line_start = self.filtered[0];
        }
        true
    }

    /// The teacher answered "no": the learner returns to the unconstrained state (thesis
    /// §3.3.1.2) with an empty tank, and does not switch on again before the motion has left
    /// the rejected line (see the module docs).
    pub fn reject(&mut self) {
        self.rejected = self.constrained;
        self.constrained = false;
        self.tank = 0.0;
    }

    /// Whether a rejected line is still under way.
    pub fn rejecting(&self) -> bool {
        self.rejected
    }

    /// A gripper command: forgets the filtered points, the tank, the state and any rejection,
    /// so the next interaction segment is detected afresh.
    pub fn reset(&mut self) {
        *self = Detector::new(self.calibration);
    }
}

/// Runs the detector over a whole trajectory: the state after each position, and the frames
/// where it switched.
pub fn replay(
    calibration: Calibration,
    positions: &[Vector3<f64>],
) -> (Vec<bool>, Vec<(usize, Switch)>) {
    let mut detector = Detector::new(calibration);
    let mut states = Vec::with_capacity(positions.len());
    let mut switches = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        if let Some(s) = detector.push(*p) {
            switches.push((i, s));
        }
        states.push(detector.constrained());
    }
    (states, switches)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(radius: f64, n: usize) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| {
                let a = i as f64 * 0.002 / radius;
                Vector3::new(radius * a.cos(), radius * a.sin(), 0.3)
            })
            .collect()
    }

    fn line(from: Vector3<f64>, dir: Vector3<f64>, n: usize) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| from + dir.normalize() * (i as f64 * 0.002))
            .collect()
    }

    #[test]
    fn a_straight_line_switches_on_and_a_circle_does_not() {
        let calibration = Calibration::default();
        let (states, switches) = replay(calibration, &line(Vector3::zeros(), Vector3::x(), 200));
        assert_eq!(switches.len(), 1);
        assert!(switches[0].1.constrained && *states.last().unwrap());
        let (states, switches) = replay(calibration, &arc(0.12, 600));
        assert!(switches.is_empty() && !states.iter().any(|s| *s));
    }

    #[test]
    fn leaving_the_line_switches_back_off() {
        let mut path = line(Vector3::new(0.12, 0.0, 0.3), -Vector3::x(), 150);
        path.extend(
            arc(0.12, 400)
                .into_iter()
                .map(|p| p - Vector3::new(0.42, 0.0, 0.0)),
        );
        let (_, switches) = replay(Calibration::default(), &path);
        let flags: Vec<bool> = switches.iter().map(|(_, s)| s.constrained).collect();
        assert_eq!(flags, vec![true, false]);
    }

    #[test]
    fn a_no_answer_returns_to_unconstrained() {
        let mut detector = Detector::new(Calibration::default());
        for p in line(Vector3::zeros(), Vector3::y(), 200) {
            detector.push(p);
        }
        assert!(detector.constrained());
        detector.reject();
        assert!(!detector.constrained() && detector.tank() == 0.0);
    }

    #[test]
    fn a_rejected_line_does_not_switch_on_again_until_left() {
        let mut path = line(Vector3::new(0.12, 0.0, 0.3), -Vector3::x(), 600);
        let end = *path.last().unwrap();
        path.extend(
            arc(0.12, 400)
                .into_iter()
                .map(|p| p + end - Vector3::x() * 0.12),
        );
        let end = *path.last().unwrap();
        path.extend(line(end, Vector3::y(), 300));
        let mut detector = Detector::new(Calibration::default());
        let mut on = Vec::new();
        for (i, p) in path.iter().enumerate() {
            if detector.push(*p).is_some_and(|s| s.constrained) {
                on.push(i);
                detector.reject();
            }
        }
        // Once on the 1.2 m line, not again on it, and once more on the new line.
        assert_eq!(on.len(), 2, "{on:?}");
        assert!(on[0] < 600 && on[1] > 1000, "{on:?}");
    }

    #[test]
    fn a_reset_forgets_the_line() {
        let mut detector = Detector::new(Calibration::default());
        let path = line(Vector3::zeros(), Vector3::x(), 400);
        for p in &path[..200] {
            detector.push(*p);
        }
        assert!(detector.constrained());
        detector.reset();
        assert!(!detector.constrained() && detector.tank() == 0.0);
        // The line goes on: it must be detected again from scratch, 2·D_F plus two points on.
        let switched = path[200..]
            .iter()
            .position(|p| detector.push(*p).is_some())
            .unwrap();
        assert!((path[200 + switched] - path[200]).norm() >= 0.15 - 1e-9);
    }
}
