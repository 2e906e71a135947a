//! Time parameterization within the joint velocity and acceleration limits.
//!
//! A path is a sequence of waypoints followed through a parameter u (u = i at waypoint i).
//! Two interpolations are used:
//! - `Linear`: straight joint-space pieces, the arm stopping at every waypoint. Each piece
//!   gets the time-optimal trapezoidal profile in u whose peak speed and acceleration put
//!   every joint at or under its limits (|q̇ⱼ| = |Δqⱼ|·u̇, |q̈ⱼ| = |Δqⱼ|·ü).
//! - `Cubic`: a monotone cubic (Fritsch–Carlson) through dense waypoints, so that velocity
//!   is continuous and no joint overshoots its waypoints (hence its limits), with one
//!   trapezoidal profile in u for the whole path. With D1ⱼ = max |qⱼ'(u)| and
//!   D2ⱼ = max |qⱼ''(u)| (exact per cubic piece), u̇ ≤ vⱼ/D1ⱼ and u̇² ≤ aⱼ/(2·D2ⱼ),
//!   ü ≤ aⱼ/(2·D1ⱼ) give |q̇ⱼ| ≤ vⱼ and |q̈ⱼ| = |qⱼ'ü + qⱼ''u̇²| ≤ aⱼ.
//!
//! Every segment starts and ends at rest.

use serde::{Deserialize, Serialize};

/// A rest-to-rest trapezoidal (or triangular) profile covering `length` in parameter space.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Trapezoid {
    /// Distance covered (parameter units).
    pub length: f64,
    /// Peak speed reached.
    pub speed: f64,
    /// Acceleration (and deceleration) magnitude.
    pub accel: f64,
    /// Time spent accelerating (and, symmetrically, decelerating).
    pub t_accel: f64,
    /// Total duration.
    pub duration: f64,
}

impl Trapezoid {
    /// The fastest profile under `max_speed` and `max_accel` (both positive).
    pub fn new(length: f64, max_speed: f64, max_accel: f64) -> Trapezoid {
        if length <= 0.0 || !max_speed.is_finite() || !max_accel.is_finite() {
            return Trapezoid {
                length: length.max(0.0),
                speed: 0.0,
                accel: 0.0,
                t_accel: 0.0,
                duration: 0.0,
            };
        }
        let t_accel = max_speed / max_accel;
        if max_accel * t_accel * t_accel >= length {
            // Triangular: never reaches max_speed.
            let t = (length / max_accel).sqrt();
            Trapezoid {
                length,
                speed: max_accel * t,
                accel: max_accel,
                t_accel: t,
                duration: 2.0 * t,
            }
        } else {
            let cruise = (length - max_accel * t_accel * t_accel) / max_speed;
            Trapezoid {
                length,
                speed: max_speed,
                accel: max_accel,
                t_accel,
                duration: 2.0 * t_accel + cruise,
            }
        }
    }

    /// Distance covered after time `t` (clamped to the profile).
    pub(crate) fn position(&self, t: f64) -> f64 {
        if self.duration <= 0.0 {
            return if t > 0.0 { self.length } else { 0.0 };
        }
        let t = t.clamp(0.0, self.duration);
        let ta = self.t_accel;
        if t <= ta {
            0.5 * self.accel * t * t
        } else if t >= self.duration - ta {
            let r = self.duration - t;
            self.length - 0.5 * self.accel * r * r
        } else {
            0.5 * self.accel * ta * ta + self.speed * (t - ta)
        }
    }
}

/// How a segment's waypoints are joined.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Timing {
    /// The arm stands still at its single waypoint for `duration` seconds.
    Hold {
        /// Seconds.
        duration: f64,
    },
    /// Straight pieces, one rest-to-rest profile per piece (piece i joins waypoints i, i+1).
    Linear {
        /// One profile per piece, u from 0 to 1.
        pieces: Vec<Trapezoid>,
    },
    /// A monotone cubic through all waypoints with one profile for u from 0 to n-1.
    Cubic {
        /// Tangent dq/du at every waypoint.
        tangents: Vec<Vec<f64>>,
        /// The profile.
        profile: Trapezoid,
    },
}

impl Timing {
    /// Duration in seconds.
    pub(crate) fn duration(&self) -> f64 {
        match self {
            Timing::Hold { duration } => *duration,
            Timing::Linear { pieces } => pieces.iter().map(|p| p.duration).sum(),
            Timing::Cubic { profile, .. } => profile.duration,
        }
    }

    /// The configuration `t` seconds into the segment with these waypoints.
    pub fn sample(&self, waypoints: &[Vec<f64>], t: f64) -> Vec<f64> {
        let Some(first) = waypoints.first() else {
            return Vec::new();
        };
        match self {
            Timing::Hold { .. } => first.clone(),
            Timing::Linear { pieces } => {
                let mut t = t.max(0.0);
                for (i, p) in pieces.iter().enumerate() {
                    if t <= p.duration || i + 1 == pieces.len() {
                        let u = if p.length > 0.0 {
                            p.position(t) / p.length
                        } else {
                            1.0
                        };
                        let (a, b) = (&waypoints[i], &waypoints[(i + 1).min(waypoints.len() - 1)]);
                        return a.iter().zip(b).map(|(x, y)| x + u * (y - x)).collect();
                    }
                    t -= p.duration;
                }
                first.clone()
            }
            Timing::Cubic { tangents, profile } => {
                let u = profile.position(t);
                cubic_at(waypoints, tangents, u)
            }
        }
    }
}

/// Times a path of straight pieces that stops at every waypoint.
pub(crate) fn linear(waypoints: &[Vec<f64>], vmax: &[f64], amax: &[f64]) -> Timing {
    let pieces = waypoints
        .windows(2)
        .map(|w| {
            let (mut speed, mut accel) = (f64::INFINITY, f64::INFINITY);
            for j in 0..w[0].len() {
                let d = (w[1][j] - w[0][j]).abs();
                if d > 0.0 {
                    speed = speed.min(vmax[j] / d);
                    accel = accel.min(amax[j] / d);
                }
            }
            Trapezoid::new(1.0, speed, accel)
        })
        .collect();
    Timing::Linear { pieces }
}

/// Fritsch–Carlson tangents on unit-spaced knots: zero at local extrema, the harmonic mean of
/// the neighbouring slopes elsewhere (at most twice the smaller one), the adjacent slope at the
/// ends; with tangents within three times the slopes the cubic stays monotone between knots.
fn monotone_tangents(waypoints: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = waypoints.len();
    let dof = waypoints[0].len();
    let mut tangents = vec![vec![0.0; dof]; n];
    if n < 2 {
        return tangents;
    }
    for j in 0..dof {
        let slope = |i: usize| waypoints[i + 1][j] - waypoints[i][j];
        tangents[0][j] = slope(0);
        tangents[n - 1][j] = slope(n - 2);
        for (i, tangent) in tangents.iter_mut().enumerate().take(n - 1).skip(1) {
            let (a, b) = (slope(i - 1), slope(i));
            tangent[j] = if a * b <= 0.0 {
                0.0
            } else {
                2.0 * a * b / (a + b)
            };
        }
    }
    tangents
}

/// Polynomial coefficients (a, b, c, d) of joint j on piece i: a + b·s + c·s² + d·s³.
fn coefficients(w: &[Vec<f64>], m: &[Vec<f64>], i: usize, j: usize) -> [f64; 4] {
    let delta = w[i + 1][j] - w[i][j];
    let (m0, m1) = (m[i][j], m[i + 1][j]);
    [
        w[i][j],
        m0,
        3.0 * delta - 2.0 * m0 - m1,
        m0 + m1 - 2.0 * delta,
    ]
}

/// The cubic's value at parameter `u` (0 at the first waypoint, n-1 at the last).
pub(crate) fn cubic_at(waypoints: &[Vec<f64>], tangents: &[Vec<f64>], u: f64) -> Vec<f64> {
    let n = waypoints.len();
    if n == 1 {
        return waypoints[0].clone();
    }
    let u = u.clamp(0.0, (n - 1) as f64);
    let i = (u.floor() as usize).min(n - 2);
    let s = u - i as f64;
    (0..waypoints[0].len())
        .map(|j| {
            let [a, b, c, d] = coefficients(waypoints, tangents, i, j);
            a + s * (b + s * (c + s * d))
        })
        .collect()
}

/// Times dense waypoints joined by a monotone cubic (see the module documentation).
pub(crate) fn cubic(waypoints: &[Vec<f64>], vmax: &[f64], amax: &[f64]) -> Timing {
    let n = waypoints.len();
    if n < 2 {
        return Timing::Hold { duration: 0.0 };
    }
    let tangents = monotone_tangents(waypoints);
    let dof = waypoints[0].len();
    let mut d1 = vec![0.0f64; dof];
    let mut d2 = vec![0.0f64; dof];
    for i in 0..n - 1 {
        for j in 0..dof {
            let [_, b, c, d] = coefficients(waypoints, &tangents, i, j);
            // q' = b + 2c s + 3d s², q'' = 2c + 6d s on s in [0, 1].
            let mut first = b.abs().max((b + 2.0 * c + 3.0 * d).abs());
            if d != 0.0 {
                let s = -c / (3.0 * d);
                if s > 0.0 && s < 1.0 {
                    first = first.max((b + 2.0 * c * s + 3.0 * d * s * s).abs());
                }
            }
            d1[j] = d1[j].max(first);
            d2[j] = d2[j].max((2.0 * c).abs().max((2.0 * c + 6.0 * d).abs()));
        }
    }
    let (mut speed, mut accel) = (f64::INFINITY, f64::INFINITY);
    for j in 0..dof {
        if d1[j] > 0.0 {
            speed = speed.min(vmax[j] / d1[j]);
            accel = accel.min(amax[j] / (2.0 * d1[j]));
        }
        if d2[j] > 0.0 {
            speed = speed.min((amax[j] / (2.0 * d2[j])).sqrt());
        }
    }
    let profile = Trapezoid::new((n - 1) as f64, speed, accel);
    Timing::Cubic { tangents, profile }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const V: [f64; 2] = [2.0, 1.0];
    const A: [f64; 2] = [10.0, 5.0];

    /// Largest finite-difference velocity and acceleration ratio to the limits.
    fn worst(timing: &Timing, w: &[Vec<f64>]) -> (f64, f64) {
        let dt = 1e-3;
        let n = (timing.duration() / dt).ceil() as usize;
        let qs: Vec<Vec<f64>> = (0..=n + 2)
            .map(|k| timing.sample(w, k as f64 * dt))
            .collect();
        let (mut v, mut a) = (0.0f64, 0.0f64);
        for k in 1..qs.len() - 1 {
            for j in 0..2 {
                let vel = (qs[k + 1][j] - qs[k - 1][j]) / (2.0 * dt);
                let acc = (qs[k + 1][j] - 2.0 * qs[k][j] + qs[k - 1][j]) / (dt * dt);
                v = v.max(vel.abs() / V[j]);
                a = a.max(acc.abs() / A[j]);
            }
        }
        (v, a)
    }

    fn arb_path() -> impl Strategy<Value = Vec<Vec<f64>>> {
        prop::collection::vec(
            prop::array::uniform2(-1.0..1.0f64).prop_map(|a| a.to_vec()),
            2..6,
        )
    }

    proptest! {
        #[test]
        fn linear_timing_respects_the_limits_and_ends_at_the_goal(w in arb_path()) {
            let t = linear(&w, &V, &A);
            let (v, a) = worst(&t, &w);
            prop_assert!(v <= 1.0 + 1e-3, "velocity ratio {v}");
            prop_assert!(a <= 1.0 + 1e-2, "acceleration ratio {a}");
            let end = t.sample(&w, t.duration());
            prop_assert!((end[0] - w[w.len() - 1][0]).abs() < 1e-12);
        }

        #[test]
        fn cubic_timing_respects_the_limits_and_passes_the_waypoints(
            start in prop::array::uniform2(-1.0..1.0f64), bend in -0.3..0.3f64
        ) {
            // A dense, gently curving path like the ones lines produce.
            let w: Vec<Vec<f64>> = (0..60)
                .map(|i| {
                    let s = i as f64 / 59.0;
                    vec![start[0] + 0.5 * s, start[1] + bend * (3.0 * s).sin()]
                })
                .collect();
            let t = cubic(&w, &V, &A);
            let (v, a) = worst(&t, &w);
            prop_assert!(v <= 1.0 + 1e-3, "velocity ratio {v}");
            prop_assert!(a <= 1.0 + 2e-2, "acceleration ratio {a}");
            if let Timing::Cubic { tangents, .. } = &t {
                for (i, q) in w.iter().enumerate() {
                    let at = cubic_at(&w, tangents, i as f64);
                    prop_assert!((at[0] - q[0]).abs() < 1e-12 && (at[1] - q[1]).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn a_short_move_is_triangular_and_a_long_one_cruises() {
        let short = Trapezoid::new(0.1, 2.0, 10.0);
        assert!(short.speed < 2.0 && (short.position(short.duration) - 0.1).abs() < 1e-12);
        let long = Trapezoid::new(10.0, 2.0, 10.0);
        assert_eq!(long.speed, 2.0);
        assert!((long.duration - (10.0 / 2.0 + 2.0 / 10.0)).abs() < 1e-12);
        assert!((long.position(long.duration / 2.0) - 5.0).abs() < 1e-9);
    }
}
