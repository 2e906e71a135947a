//! Per-user detector calibration (thesis §3.3.1.1): the logistic regression β0, β1 and the
//! energy tank's dissipation T_d and threshold T_s, fitted from one straight-line and one circle
//! demonstration.

use std::path::Path;

use k::nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::demo::Demo;
use crate::detector::Straightness;

/// The calibration file version: 2 since the detector samples finer and measures eq. 3.2 over a
/// window ([`Sampling`]); a version 1 file was fitted to the 5 cm signal and means nothing to it.
pub const CALIBRATION_VERSION: u32 = 2;

/// How the detector samples the path (see [`Detector`](crate::Detector)): its distance filter step D_F
/// and the window of eq. 3.2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Distance filter step D_F (m).
    pub filter_distance: f64,
    /// Eq. 3.2 is measured on filtered points this many steps apart.
    pub window: u32,
    /// Positions are averaged over this many seconds before the filter (0: not at all).
    pub smoothing: f64,
}

impl Sampling {
    /// The widest window the detector supports.
    pub const MAX_WINDOW: u32 = 12;

    /// The path one distance error spans: `2·window` filter steps (m).
    pub fn span(&self) -> f64 {
        2.0 * f64::from(self.window) * self.filter_distance
    }
}

/// The detector's sampling, chosen by measurement: D_F = 1 cm, eq. 3.2 over points 3 cm apart
/// (each error spans 6 cm of path), positions averaged over 0.1 s (a period of 10 Hz tremor).
///
/// The shortest required line it asks about is 10 cm: a descent into a fixture and the pull of
/// a handle of 10 cm were asked about and learned as lines in 10 of 10 seeds for the default
/// teacher and for a first-time teacher, 8 cm in at most 2. A line needs a whole window (6 cm)
/// plus a step per further error the tank needs, plus the last step, which the hand stopping at
/// the line's end never completes: about 9 cm. Measured with `cargo test --release -p akl-learn
/// --test detection detector_survey -- --ignored --nocapture` on the built-in tasks (10 seeds,
/// default, first-time and straight-moving teachers), both teachers' calibration circles, and
/// the 8–15 cm lines: at D_F = 5 cm (the thesis) no line under 18 cm was asked about; at 1 cm
/// without smoothing the 10 cm lines were missed in up to 4 of 10 seeds and the first-time
/// teacher's free reaches drew 14 queries (tremor shows as bends at that step); smoothing over
/// 0.06 s left 5, over 0.1 s 3 (the detector before drew 11); a 2 cm window (4 cm span) drew 57,
/// a 4 cm window missed 10 cm lines; D_F = 0.8 cm with a 4-step window drew 14 and 1.2 cm missed
/// 10 cm lines. No sampling asked about the calibration circles.
pub const SAMPLING: Sampling = Sampling {
    filter_distance: 0.01,
    window: 3,
    smoothing: 0.1,
};

/// Consecutive confidently straight distance errors needed to switch: 2, one filter step apart.
/// With 3 the first-time teacher's free reaches drew no query but 10 cm descents were asked
/// about in only 7 of 10 seeds (the survey of [`SAMPLING`]).
pub const SWITCH_POINTS: f64 = 2.0;

/// Where T_d sits between the mean squared switching probability on unconstrained motion and on
/// constrained motion: halfway, so that the tank fills only while most errors look straight.
/// Lower values let isolated straight-looking errors of curved motion add up over a whole
/// reach. Measured at the thesis's 5 cm sampling (60 demos: the default teacher, and the same
/// teacher moving straight wherever it is free to): with the 0.3 m calibration circle, queries
/// on curved motion were 12 at 0.1, 0 at 0.5 and 0 at 0.7, while every required line and 119 of
/// 130 unintended lines were asked about in each case; with a 0.12 m circle there were 124 to
/// 300 whatever the fraction. 0.5 is the fraction with a symmetric meaning; at the finer
/// sampling it leaves no query on the default teacher's curves (the survey of [`SAMPLING`]).
pub const DISSIPATION_FRACTION: f64 = 0.5;

/// How the energy tank's T_d and T_s follow from the fitted model (the thesis infers them from
/// calibration without saying how; see [`Calibration::fit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TankRule {
    /// Filtered points in a row that switch the state ([`SWITCH_POINTS`]).
    pub switch_points: f64,
    /// Where T_d sits between the two classes ([`DISSIPATION_FRACTION`]).
    pub dissipation_fraction: f64,
}

impl Default for TankRule {
    fn default() -> Self {
        TankRule {
            switch_points: SWITCH_POINTS,
            dissipation_fraction: DISSIPATION_FRACTION,
        }
    }
}

/// The parameters of the online detector for one teacher.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// File format version; always [`CALIBRATION_VERSION`].
    pub akl_calibration: u32,
    /// Logistic intercept β0.
    pub beta0: f64,
    /// Logistic slope β1 (1/m): σ(β0 + β1·d) is the probability that motion with line error d is
    /// unconstrained.
    pub beta1: f64,
    /// Tank dissipation per filtered point, T_d.
    pub tank_dissipation: f64,
    /// Tank switching threshold, T_s.
    pub tank_threshold: f64,
    /// Distance filter step D_F (m).
    pub filter_distance: f64,
    /// Eq. 3.2 is measured on filtered points this many steps apart ([`Sampling::window`]).
    #[serde(default = "default_window")]
    pub window: u32,
    /// Seconds over which positions are averaged before the filter ([`Sampling::smoothing`]).
    #[serde(default = "default_smoothing")]
    pub smoothing: f64,
}

/// The window of a file that does not give one.
fn default_window() -> u32 {
    SAMPLING.window
}

/// The smoothing of a file that does not give one.
fn default_smoothing() -> f64 {
    SAMPLING.smoothing
}

impl Default for Calibration {
    /// The calibration shipped for teachers who have not calibrated: fitted by
    /// [`Calibration::fit`] to the simulated default teacher's line and circle demonstrations
    /// (`akl calibrate --simulate`, seed 0) and rounded (a test checks the two agree).
    fn default() -> Self {
        Calibration {
            akl_calibration: CALIBRATION_VERSION,
            beta0: -7.7,
            beta1: 4650.0,
            tank_dissipation: 0.49,
            tank_threshold: 0.99,
            filter_distance: SAMPLING.filter_distance,
            window: SAMPLING.window,
            smoothing: SAMPLING.smoothing,
        }
    }
}

/// How a calibration classifies calibration data, filtered point by filtered point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Separation {
    /// Filtered points of the line.
    pub line_points: usize,
    /// Of those, classified constrained.
    pub line_right: usize,
    /// Filtered points of the circle.
    pub circle_points: usize,
    /// Of those, classified unconstrained.
    pub circle_right: usize,
}

/// Why calibration failed.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum CalibrationError {
    /// A demonstration is too short to give distance errors.
    #[error("the {which} demonstration is too short: {points} distance errors after the {filter} m filter (need at least {needed})")]
    TooShort {
        /// `line` or `circle`.
        which: &'static str,
        /// Errors it gave.
        points: usize,
        /// Needed.
        needed: usize,
        /// D_F.
        filter: f64,
    },
    /// The line and circle cannot be told apart.
    #[error("the line and the circle cannot be told apart (mean line error {line:.4} m, mean circle error {circle:.4} m): demonstrate a straighter line and a rounder circle")]
    Indistinguishable {
        /// Mean error on the line.
        line: f64,
        /// Mean error on the circle.
        circle: f64,
    },
    /// A calibration file is malformed.
    #[error("{0}")]
    Invalid(String),
    /// The file's version is not the one this build reads.
    #[error("unsupported akl_calibration version {0} (this build reads {CALIBRATION_VERSION}: the detector's signal changed, so calibrate again with `akl calibrate`)")]
    Version(u32),
    /// The detector's window is outside what it supports.
    #[error("window {0} is outside 1..={max}", max = Sampling::MAX_WINDOW)]
    Window(u32),
    /// The logistic model's coefficients are unusable.
    #[error("beta1 must be positive and beta0 finite")]
    Coefficients,
    /// The tank or smoothing parameters are unusable.
    #[error("0 ≤ tank_dissipation < 1 (else the tank never fills), tank_threshold > 0 and 0 ≤ smoothing ≤ 1 s are required")]
    Tank,
    /// The distance filter step is outside what the detector can use.
    #[error("filter_distance {0} m is outside {min}..={max} m: a shorter step samples the hand's tremor rather than its path, and with a longer one no line shorter than 2·window steps is ever asked about", min = Calibration::FILTER_DISTANCES.start(), max = Calibration::FILTER_DISTANCES.end())]
    FilterDistance(f64),
}

/// Fewest distance errors per demonstration for a meaningful fit.
const MIN_POINTS: usize = 4;

impl Calibration {
    /// The distance filter steps a calibration may give (m): 1 mm to 10 cm, round the 1 cm the
    /// detector was tuned at and the thesis's 5 cm ([`SAMPLING`]).
    pub const FILTER_DISTANCES: std::ops::RangeInclusive<f64> = 0.001..=0.1;

    /// Pr(unconstrained | d) = σ(β0 + β1·d), the logistic model of eq. 3.3.
    pub fn probability_unconstrained(&self, d: f64) -> f64 {
        1.0 / (1.0 + (-(self.beta0 + self.beta1 * d)).exp())
    }

    /// Fits a calibration to a straight-line demonstration (labelled constrained) and a circle
    /// demonstration (labelled unconstrained), given as end-effector motions.
    ///
    /// β0, β1 maximize the likelihood (Newton's method with a tiny ridge, so perfectly separable
    /// data still gives finite parameters). T_d and T_s then follow from the fitted model on the
    /// same data: with m_c and m_u the mean squared switching probabilities on the line and on
    /// the circle, T_d = m_u + [`DISSIPATION_FRACTION`]·(m_c − m_u) and
    /// T_s = [`SWITCH_POINTS`]·(m_c − T_d), raised if needed so that the tank never fills on the
    /// circle itself.
    pub fn fit(line: &Motion, circle: &Motion) -> Result<Calibration, CalibrationError> {
        Calibration::fit_with(line, circle, SAMPLING, &TankRule::default())
    }

    /// [`Calibration::fit`] at another sampling and with another rule for the tank parameters
    /// (for surveys).
    pub fn fit_with(
        line: &Motion,
        circle: &Motion,
        sampling: Sampling,
        rule: &TankRule,
    ) -> Result<Calibration, CalibrationError> {
        let line_errors = filtered_errors(line, sampling);
        let circle_errors = filtered_errors(circle, sampling);
        for (which, errors) in [("line", &line_errors), ("circle", &circle_errors)] {
            if errors.len() < MIN_POINTS {
                return Err(CalibrationError::TooShort {
                    which,
                    points: errors.len(),
                    needed: MIN_POINTS,
                    filter: sampling.filter_distance,
                });
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (line_mean, circle_mean) = (mean(&line_errors), mean(&circle_errors));
        if circle_mean < 2.0 * line_mean || circle_mean - line_mean < 1e-3 {
            return Err(CalibrationError::Indistinguishable {
                line: line_mean,
                circle: circle_mean,
            });
        }
        let (beta0, beta1) = logistic_fit(&line_errors, &circle_errors);
        let mut calibration = Calibration {
            akl_calibration: CALIBRATION_VERSION,
            beta0,
            beta1,
            tank_dissipation: 0.0,
            tank_threshold: 0.0,
            filter_distance: sampling.filter_distance,
            window: sampling.window,
            smoothing: sampling.smoothing,
        };
        let squared_switch = |errors: &[f64]| {
            mean(
                &errors
                    .iter()
                    .map(|d| (1.0 - calibration.probability_unconstrained(*d)).powi(2))
                    .collect::<Vec<_>>(),
            )
        };
        let (m_c, m_u) = (squared_switch(&line_errors), squared_switch(&circle_errors));
        calibration.tank_dissipation = m_u + rule.dissipation_fraction * (m_c - m_u);
        calibration.tank_threshold = rule.switch_points * (m_c - calibration.tank_dissipation);
        let mut tank: f64 = 0.0;
        let mut peak: f64 = 0.0;
        for d in &circle_errors {
            let p = 1.0 - calibration.probability_unconstrained(*d);
            tank = (tank + p * p - calibration.tank_dissipation).max(0.0);
            peak = peak.max(tank);
        }
        calibration.tank_threshold = calibration.tank_threshold.max(1.2 * peak);
        Ok(calibration)
    }

    /// The fewest filtered points in a row that can switch the detector's state: each adds at
    /// most 1 − T_d to the tank, which switches at T_s. The detector's delay in filtered points
    /// (at least 1).
    pub fn switch_points(&self) -> u32 {
        let per_point = 1.0 - self.tank_dissipation;
        if per_point <= 0.0 {
            return 1;
        }
        (self.tank_threshold / per_point).ceil().clamp(1.0, 100.0) as u32
    }

    /// The detector's sampling: its filter step and window.
    pub fn sampling(&self) -> Sampling {
        Sampling {
            filter_distance: self.filter_distance,
            window: self.window,
            smoothing: self.smoothing,
        }
    }

    /// The line distance error (m) at which motion is as likely constrained as not.
    pub fn boundary(&self) -> f64 {
        -self.beta0 / self.beta1
    }

    /// How this calibration classifies the filtered points of a line and a circle.
    pub fn separation(&self, line: &Motion, circle: &Motion) -> Separation {
        let classify = |motion: &Motion, unconstrained: bool| {
            let errors = filtered_errors(motion, self.sampling());
            let right = errors
                .iter()
                .filter(|d| (self.probability_unconstrained(**d) > 0.5) == unconstrained)
                .count();
            (errors.len(), right)
        };
        let (line_points, line_right) = classify(line, false);
        let (circle_points, circle_right) = classify(circle, true);
        Separation {
            line_points,
            line_right,
            circle_points,
            circle_right,
        }
    }

    /// Writes the calibration file atomically.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let text = akl_tsr::io::to_readable_json(self).map_err(std::io::Error::other)?;
        akl_tsr::io::write_atomic(path, text.as_bytes())
    }

    /// Reads a calibration file; errors name it.
    pub fn load(path: &Path) -> Result<Calibration, CalibrationError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CalibrationError::Invalid(format!("{}: {e}", path.display())))?;
        Calibration::from_json(&text)
            .map_err(|e| CalibrationError::Invalid(format!("{}: {e}", path.display())))
    }

    /// Parses and validates a calibration from the JSON text of a calibration file; a syntax
    /// error names the line and column.
    pub fn from_json(text: &str) -> Result<Calibration, CalibrationError> {
        let calibration: Calibration = serde_json::from_str(text).map_err(|e| {
            let (line, column, message) = akl_tsr::describe_json_error(&e, text);
            CalibrationError::Invalid(format!("line {line}, column {column}: {message}"))
        })?;
        calibration.validate()?;
        Ok(calibration)
    }

    /// Checks the version and that every parameter is usable.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        if self.akl_calibration != CALIBRATION_VERSION {
            return Err(CalibrationError::Version(self.akl_calibration));
        }
        if !(1..=Sampling::MAX_WINDOW).contains(&self.window) {
            return Err(CalibrationError::Window(self.window));
        }
        if !self.beta1.is_finite() || self.beta1 <= 0.0 || !self.beta0.is_finite() {
            return Err(CalibrationError::Coefficients);
        }
        let usable = (0.0..1.0).contains(&self.tank_dissipation)
            && self.tank_threshold > 0.0
            && self.tank_threshold.is_finite()
            && (0.0..=1.0).contains(&self.smoothing);
        if !usable {
            return Err(CalibrationError::Tank);
        }
        if !Self::FILTER_DISTANCES.contains(&self.filter_distance) {
            return Err(CalibrationError::FilterDistance(self.filter_distance));
        }
        Ok(())
    }
}

/// A recorded hand motion as calibration reads it: end-effector positions and their times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Motion {
    /// Time of each position (s, increasing).
    pub times: Vec<f64>,
    /// End-effector positions (m).
    pub positions: Vec<Vector3<f64>>,
}

impl Motion {
    /// The end-effector motion of a recorded demonstration.
    pub fn of(demo: &Demo) -> Motion {
        Motion {
            times: demo.times.clone(),
            positions: demo.ee.iter().map(|p| p.translation.vector).collect(),
        }
    }
}

/// The eq. 3.2 distance errors of a whole motion at `sampling`, as the detector sees them.
pub(crate) fn filtered_errors(motion: &Motion, sampling: Sampling) -> Vec<f64> {
    let mut signal = Straightness::new(sampling);
    motion
        .times
        .iter()
        .zip(&motion.positions)
        .filter_map(|(t, p)| signal.push(*t, *p))
        .collect()
}

/// Errors are fitted in centimetres so that β0 and β1 have similar magnitudes.
const SCALE: f64 = 100.0;
/// The ridge penalty ½·RIDGE·(β0² + β1_cm²) that keeps separable data finite.
const RIDGE: f64 = 1e-3;

/// Maximum-likelihood logistic regression of "unconstrained" on d: constrained samples are
/// label 0, unconstrained label 1. Errors are scaled to centimetres inside for conditioning.
fn logistic_fit(constrained: &[f64], unconstrained: &[f64]) -> (f64, f64) {
    let samples: Vec<(f64, f64)> = constrained
        .iter()
        .map(|d| (d * SCALE, 0.0))
        .chain(unconstrained.iter().map(|d| (d * SCALE, 1.0)))
        .collect();
    let (mut b0, mut b1) = (0.0f64, 0.0f64);
    for _ in 0..100 {
        let (mut g0, mut g1, mut h00, mut h01, mut h11) = (0.0, -RIDGE * b1, RIDGE, 0.0, RIDGE);
        g0 -= RIDGE * b0;
        for (x, y) in &samples {
            let p = 1.0 / (1.0 + (-(b0 + b1 * x)).exp());
            let w = p * (1.0 - p);
            g0 += y - p;
            g1 += (y - p) * x;
            h00 += w;
            h01 += w * x;
            h11 += w * x * x;
        }
        let det = h00 * h11 - h01 * h01;
        if det.abs() < 1e-300 {
            break;
        }
        let s0 = (h11 * g0 - h01 * g1) / det;
        let s1 = (h00 * g1 - h01 * g0) / det;
        b0 += s0;
        b1 += s1;
        if s0.abs() + s1.abs() < 1e-10 {
            break;
        }
    }
    (b0, b1 * SCALE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` positions at 100 Hz.
    fn motion(n: usize, at: impl Fn(usize) -> Vector3<f64>) -> Motion {
        Motion {
            times: (0..n).map(|i| i as f64 * 0.01).collect(),
            positions: (0..n).map(at).collect(),
        }
    }

    fn noisy_line(n: usize, noise: f64) -> Motion {
        motion(n, |i| {
            let s = i as f64 * 0.002;
            let wobble = noise * ((i as f64) * 0.7).sin();
            Vector3::new(s, wobble, 0.3 + wobble * 0.5)
        })
    }

    fn circle(n: usize, radius: f64) -> Motion {
        motion(n, |i| {
            let a = i as f64 * 0.002 / radius;
            Vector3::new(radius * a.cos(), radius * a.sin(), 0.3)
        })
    }

    #[test]
    fn the_fit_separates_line_from_circle_and_the_tank_respects_both() {
        let line = noisy_line(400, 0.002);
        let circle = circle(1200, 0.12);
        let calibration = Calibration::fit(&line, &circle).unwrap();
        assert!(calibration.beta1 > 0.0);
        let line_errors = filtered_errors(&line, SAMPLING);
        let circle_errors = filtered_errors(&circle, SAMPLING);
        assert!(line_errors
            .iter()
            .all(|d| calibration.probability_unconstrained(*d) < 0.5));
        assert!(circle_errors
            .iter()
            .all(|d| calibration.probability_unconstrained(*d) > 0.5));
        let (_, on_line) = crate::detector::Detector::replay(calibration, &line);
        assert_eq!(on_line.len(), 1, "the line switches the detector on once");
        let (_, on_circle) = crate::detector::Detector::replay(calibration, &circle);
        assert!(on_circle.is_empty(), "the circle never switches it");
    }

    #[test]
    fn the_fit_maximizes_the_penalized_likelihood() {
        let line = filtered_errors(&noisy_line(400, 0.004), SAMPLING);
        let circle = filtered_errors(&circle(1200, 0.3), SAMPLING);
        let (b0, b1) = logistic_fit(&line, &circle);
        let log_likelihood = |b0: f64, b1: f64| {
            let ll = |d: &f64, y: f64| {
                let p = 1.0 / (1.0 + (-(b0 + b1 * d)).exp());
                if y > 0.5 {
                    p.ln()
                } else {
                    (1.0 - p).ln()
                }
            };
            line.iter().map(|d| ll(d, 0.0)).sum::<f64>()
                + circle.iter().map(|d| ll(d, 1.0)).sum::<f64>()
        };
        let objective = |b0: f64, b1: f64| {
            log_likelihood(b0, b1) - 0.5 * RIDGE * (b0 * b0 + (b1 / SCALE).powi(2))
        };
        let best = objective(b0, b1);
        for (d0, d1) in [
            (0.05, 0.0),
            (-0.05, 0.0),
            (0.0, 5.0),
            (0.0, -5.0),
            (0.05, 5.0),
            (-0.05, -5.0),
        ] {
            assert!(objective(b0 + d0, b1 + d1) <= best + 1e-9);
        }
    }

    #[test]
    fn degenerate_calibration_data_is_a_clear_error() {
        let line = noisy_line(400, 0.002);
        assert!(matches!(
            Calibration::fit(&noisy_line(20, 0.002), &circle(1200, 0.12)),
            Err(CalibrationError::TooShort { which: "line", .. })
        ));
        let still = motion(500, |_| Vector3::new(0.1, 0.2, 0.3));
        assert!(matches!(
            Calibration::fit(&line, &still),
            Err(CalibrationError::TooShort {
                which: "circle",
                ..
            })
        ));
        assert!(matches!(
            Calibration::fit(&line, &noisy_line(400, 0.002)),
            Err(CalibrationError::Indistinguishable { .. })
        ));
    }

    #[test]
    fn the_default_is_valid() {
        assert_eq!(Calibration::default().validate(), Ok(()));
        assert_eq!(Calibration::default().switch_points(), 2);
        let leaky = Calibration {
            tank_dissipation: 1.0,
            ..Calibration::default()
        };
        assert_eq!(leaky.validate(), Err(CalibrationError::Tank));
        for absurd in [0.0, -0.01, 1e-9, 0.5, 1e9, f64::NAN] {
            let step = Calibration {
                filter_distance: absurd,
                ..Calibration::default()
            };
            assert!(
                matches!(step.validate(), Err(CalibrationError::FilterDistance(d)) if d.to_bits() == absurd.to_bits()),
                "{absurd}"
            );
        }
    }

    #[test]
    fn calibration_text_reads_back_and_errors_say_where_or_which_rule() {
        let text = akl_tsr::io::to_readable_json(&Calibration::default()).unwrap();
        assert_eq!(Calibration::from_json(&text), Ok(Calibration::default()));
        let Err(CalibrationError::Invalid(message)) = Calibration::from_json("{\n  \"beta0\": x")
        else {
            panic!("a syntax error is Invalid");
        };
        assert!(message.starts_with("line 2, column "), "{message}");
        let old = text.replace("\"akl_calibration\": 2", "\"akl_calibration\": 1");
        assert_eq!(
            Calibration::from_json(&old),
            Err(CalibrationError::Version(1))
        );
    }
}
