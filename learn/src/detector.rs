//! The online constraint detector of thesis §3.3.1.1 (eqs. 3.2–3.5).
//!
//! End-effector positions are thinned by a distance filter (D_F), each new filtered point gives
//! the perpendicular distance d_i of the newest point from the line through two earlier ones
//! (eq. 3.2), a per-user logistic regression turns d_i into the probability that the constraint
//! state switches (eq. 3.3), and an energy tank decides when it does (eqs. 3.4–3.5). One
//! [`Detector::push`] per recorded frame: constant time, no allocation.
//!
//! **Resolution and window.** The thesis filters at D_F = 5 cm and measures eq. 3.2 on three
//! consecutive filtered points, so the first distance error needs 10 cm of line and the tank
//! two or more of them: lines under about 18 cm were never asked about. Here the filter step is
//! finer ([`Sampling::filter_distance`]) and eq. 3.2 is measured on points
//! [`Sampling::window`] steps apart — the newest filtered point against the line through the
//! points `window` and `2·window` steps back — so each error still spans a few centimetres of
//! path (what separates a line from a curve under hand tremor), but a new error comes every
//! step. Before the filter each sample is averaged with the samples of the last
//! [`Sampling::smoothing`] seconds, and each filtered point is the mean of the smoothed samples since the
//! previous one: this takes out the sensor noise and the 8–12 Hz tremor that a 1 cm step would
//! otherwise see as bends (on a straight line both move nothing off it). [`SAMPLING`] gives the
//! values chosen and the measurement behind them.
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

#[cfg(doc)]
use crate::calibration::SAMPLING;
use crate::calibration::{Calibration, Motion, Sampling};
use crate::line_error::line_error;

/// The most filtered points the detector keeps: enough for the widest window
/// ([`Sampling::MAX_WINDOW`]) and the points a switch looks back over.
const KEPT: usize = 32;

/// The most samples the smoothing averages: 0.1 s ([`SAMPLING`]) at up to 1,280 Hz. At higher
/// rates the average covers the latest 128 samples only.
const SMOOTHED: usize = 128;

/// The moving average of the samples of the last `span` seconds, streaming.
#[derive(Debug, Clone)]
struct Smoother {
    span: f64,
    samples: [(f64, Vector3<f64>); SMOOTHED],
    /// Index of the oldest sample in the average, and how many are in it.
    first: usize,
    len: usize,
    sum: Vector3<f64>,
}

impl Smoother {
    fn new(span: f64) -> Self {
        Smoother {
            span,
            samples: [(0.0, Vector3::zeros()); SMOOTHED],
            first: 0,
            len: 0,
            sum: Vector3::zeros(),
        }
    }

    /// Adds the sample `p` at time `t` and returns the mean of the samples since `t − span`
    /// (`p` itself when `span` is 0).
    fn push(&mut self, t: f64, p: Vector3<f64>) -> Vector3<f64> {
        while self.len > 0 && (self.len == SMOOTHED || self.samples[self.first].0 <= t - self.span)
        {
            self.sum -= self.samples[self.first].1;
            self.first = (self.first + 1) % SMOOTHED;
            self.len -= 1;
        }
        self.samples[(self.first + self.len) % SMOOTHED] = (t, p);
        self.len += 1;
        self.sum += p;
        self.sum / self.len as f64
    }
}

/// The distance signal of eq. 3.2 at a [`Sampling`]: the distance filter and the window of
/// filtered points, streaming. Shared by the detector and its calibration, so both see the
/// same errors.
#[derive(Debug, Clone)]
pub(crate) struct Straightness {
    sampling: Sampling,
    smoother: Smoother,
    /// The sample that completed the last filter step (the next step is measured from it).
    anchor: Vector3<f64>,
    /// Sum and count of the samples of the step under way.
    sum: Vector3<f64>,
    samples: u32,
    started: bool,
    /// The last [`KEPT`] filtered points, a ring; `count` is how many were ever filtered.
    points: [Vector3<f64>; KEPT],
    count: usize,
}

impl Straightness {
    /// An empty signal at `sampling` (its window must not exceed [`Sampling::MAX_WINDOW`]).
    pub(crate) fn new(sampling: Sampling) -> Self {
        Straightness {
            sampling,
            smoother: Smoother::new(sampling.smoothing),
            anchor: Vector3::zeros(),
            sum: Vector3::zeros(),
            samples: 0,
            started: false,
            points: [Vector3::zeros(); KEPT],
            count: 0,
        }
    }

    /// Takes the position `p` recorded at time `t` (s, increasing); returns the distance error d
    /// when it completed a filtered point with `2·window` points before it.
    ///
    /// Positions are smoothed first (the mean over the last [`Sampling::smoothing`] seconds). The first
    /// smoothed position is the first filtered point; after it, a step completes at the first
    /// one at least D_F from the one that completed the step before, and the filtered point is
    /// the mean of the step's smoothed positions (up to and including that one).
    pub(crate) fn push(&mut self, t: f64, p: Vector3<f64>) -> Option<f64> {
        let p = self.smoother.push(t, p);
        if !self.started {
            self.started = true;
            self.anchor = p;
            self.keep(p);
            return None;
        }
        self.sum += p;
        self.samples += 1;
        if (p - self.anchor).norm_squared()
            < self.sampling.filter_distance * self.sampling.filter_distance
        {
            return None;
        }
        let mean = self.sum / f64::from(self.samples);
        self.anchor = p;
        self.sum = Vector3::zeros();
        self.samples = 0;
        self.keep(mean);
        let w = self.sampling.window as usize;
        (self.count > 2 * w).then(|| line_error(&self.back(2 * w), &self.back(w), &self.back(0)))
    }

    fn keep(&mut self, p: Vector3<f64>) {
        self.points[self.count % KEPT] = p;
        self.count += 1;
    }

    /// The filtered point `steps` before the newest one (the oldest kept, if fewer are kept).
    pub(crate) fn back(&self, steps: usize) -> Vector3<f64> {
        let steps = steps.min(self.count.saturating_sub(1)).min(KEPT - 1);
        self.points[(self.count - 1 - steps) % KEPT]
    }
}

/// What a frame did to the detector's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Switch {
    /// The new state: true = constrained (moving in a line).
    pub constrained: bool,
    /// The line distance error d_i (m) of the filtered point that tipped the tank.
    pub error: f64,
    /// Where the detected line starts: the first filtered point of the straight errors that
    /// filled the tank (the start of the window of the first of them).
    pub line_start: Vector3<f64>,
}

/// The streaming detector: feed it end-effector positions in order.
#[derive(Debug, Clone)]
pub struct Detector {
    calibration: Calibration,
    signal: Straightness,
    /// Filtered points from the start of a switching run of errors back to the newest point:
    /// `2·window` for the first error's window plus one per further error the tank needs.
    look_back: usize,
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
        let sampling = calibration.sampling();
        let look_back = 2 * sampling.window as usize + calibration.switch_points() as usize - 1;
        Detector {
            calibration,
            signal: Straightness::new(sampling),
            look_back,
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

    /// Takes the end-effector position `p` recorded at time `t` (s, increasing); returns the
    /// switch it caused, if any.
    pub fn push(&mut self, t: f64, p: Vector3<f64>) -> Option<Switch> {
        let d = self.signal.push(t, p)?;
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
            self.line_start = self.signal.back(self.look_back);
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

    /// Runs the detector over a whole trajectory (positions and their times): the state after each
    /// position, and the frames where it switched.
    pub fn replay(calibration: Calibration, motion: &Motion) -> (Vec<bool>, Vec<(usize, Switch)>) {
        let mut detector = Detector::new(calibration);
        let mut states = Vec::with_capacity(motion.positions.len());
        let mut switches = Vec::new();
        for (i, (t, p)) in motion.times.iter().zip(&motion.positions).enumerate() {
            if let Some(s) = detector.push(*t, *p) {
                switches.push((i, s));
            }
            states.push(detector.constrained());
        }
        (states, switches)
    }
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

    /// The positions recorded at 100 Hz (20 cm/s along the paths above).
    fn timed(path: Vec<Vector3<f64>>) -> Motion {
        Motion {
            times: (0..path.len()).map(|i| i as f64 * 0.01).collect(),
            positions: path,
        }
    }

    /// Pushes `path` from time `t0` on; the frames that switched the state on.
    fn push_all(detector: &mut Detector, path: &[Vector3<f64>], t0: f64) -> Vec<usize> {
        (0..path.len())
            .filter(|&i| {
                detector
                    .push(t0 + i as f64 * 0.01, path[i])
                    .is_some_and(|s| s.constrained)
            })
            .collect()
    }

    #[test]
    fn a_straight_line_switches_on_and_a_circle_does_not() {
        let calibration = Calibration::default();
        let (states, switches) = Detector::replay(
            calibration,
            &timed(line(Vector3::zeros(), Vector3::x(), 200)),
        );
        assert_eq!(switches.len(), 1);
        assert!(switches[0].1.constrained && *states.last().unwrap());
        let (states, switches) = Detector::replay(calibration, &timed(arc(0.12, 600)));
        assert!(switches.is_empty() && !states.iter().any(|s| *s));
    }

    #[test]
    fn a_ten_centimetre_line_between_curves_switches_on_before_it_ends() {
        let mut path = arc(0.3, 150);
        let corner = *path.last().unwrap();
        let down = line(corner, -Vector3::z(), 51);
        let end = *down.last().unwrap();
        path.extend(&down[1..]);
        path.extend(arc(0.3, 150).into_iter().map(|p| p - arc(0.3, 1)[0] + end));
        let (_, switches) = Detector::replay(Calibration::default(), &timed(path.clone()));
        let on: Vec<_> = switches.iter().filter(|(_, s)| s.constrained).collect();
        assert_eq!(on.len(), 1, "{switches:?}");
        let (frame, switch) = on[0];
        assert!(*frame > 150 && *frame < 200, "frame {frame}");
        assert!((switch.line_start - corner).norm() < 0.02, "{switch:?}");
    }

    #[test]
    fn leaving_the_line_switches_back_off() {
        let mut path = line(Vector3::new(0.12, 0.0, 0.3), -Vector3::x(), 150);
        path.extend(
            arc(0.12, 400)
                .into_iter()
                .map(|p| p - Vector3::new(0.42, 0.0, 0.0)),
        );
        let (_, switches) = Detector::replay(Calibration::default(), &timed(path));
        let flags: Vec<bool> = switches.iter().map(|(_, s)| s.constrained).collect();
        assert_eq!(flags, vec![true, false]);
    }

    #[test]
    fn a_no_answer_returns_to_unconstrained() {
        let mut detector = Detector::new(Calibration::default());
        push_all(
            &mut detector,
            &line(Vector3::zeros(), Vector3::y(), 200),
            0.0,
        );
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
            if detector
                .push(i as f64 * 0.01, *p)
                .is_some_and(|s| s.constrained)
            {
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
        let calibration = Calibration::default();
        let mut detector = Detector::new(calibration);
        let path = line(Vector3::zeros(), Vector3::x(), 400);
        push_all(&mut detector, &path[..200], 0.0);
        assert!(detector.constrained());
        detector.reset();
        assert!(!detector.constrained() && detector.tank() == 0.0);
        // The line goes on: it must be detected again from scratch, a whole window on.
        let on = push_all(&mut detector, &path[200..], 2.0);
        assert_eq!(on.len(), 1);
        assert!((path[200 + on[0]] - path[200]).norm() >= calibration.sampling().span());
    }
}
