//! Hand-like motion primitives: minimum-jerk timing and hand noise.

use k::nalgebra::Vector3;
use rand::Rng;
use rand_distr_free::gaussian;

/// The minimum-jerk progress s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ of a point-to-point reach (Flash & Hogan
/// 1985): how far along its path a hand is at normalized time τ ∈ [0, 1].
pub(super) fn min_jerk(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// Tremor (a few sinusoids at 8–12 Hz with random phases per axis) plus white sensor noise.
#[derive(Debug, Clone)]
pub struct Noise {
    components: [(f64, f64, Vector3<f64>); 3],
    tremor: f64,
    sensor: f64,
}

impl Noise {
    /// Noise with tremor amplitude `tremor` and sensor standard deviation `sensor` (m).
    pub fn new<R: Rng>(tremor: f64, sensor: f64, rng: &mut R) -> Self {
        let mut component = || {
            let frequency = rng.gen_range(8.0..12.0);
            let phase = rng.gen_range(0.0..std::f64::consts::TAU);
            let direction = Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            );
            (frequency, phase, direction.normalize())
        };
        Noise {
            components: [component(), component(), component()],
            tremor,
            sensor,
        }
    }

    /// The displacement at time `t` (tremor) plus a fresh sensor sample.
    pub fn sample<R: Rng>(&self, t: f64, rng: &mut R) -> Vector3<f64> {
        let mut d = Vector3::zeros();
        for (frequency, phase, direction) in &self.components {
            d += direction
                * (self.tremor / 3.0)
                * (std::f64::consts::TAU * frequency * t + phase).sin();
        }
        d + Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng)) * self.sensor
    }
}

/// A standard normal sample without an extra crate (Box–Muller).
mod rand_distr_free {
    use rand::Rng;

    /// One draw from N(0, 1).
    pub(super) fn gaussian<R: Rng>(rng: &mut R) -> f64 {
        let u: f64 = rng.gen_range(f64::EPSILON..1.0);
        let v: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        (-2.0 * u.ln()).sqrt() * v.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_jerk_starts_and_ends_at_rest() {
        assert_eq!(min_jerk(0.0), 0.0);
        assert!((min_jerk(1.0) - 1.0).abs() < 1e-12);
        assert!((min_jerk(0.5) - 0.5).abs() < 1e-12);
        let h = 1e-6;
        assert!(min_jerk(h) / h < 1e-9 && (1.0 - min_jerk(1.0 - h)) / h < 1e-9);
    }
}
