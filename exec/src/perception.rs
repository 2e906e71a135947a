//! What a perception system reports: the true placement of every movable object with
//! estimation noise. The planner plans, and keyframes are grounded, on what was perceived; the
//! simulation runs the true world.
//!
//! Noise is drawn per object, independently: a Gaussian offset along world x and y and a
//! Gaussian turn about the world vertical through the object's centre. The height and tilt are
//! left as they are: an object standing on a known support is seen at the support's height,
//! and a tabletop pose estimate's error lies in the plane.

use akl_scene::World;
use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Standard deviations of pose estimation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseNoise {
    /// Position error along each of world x and y (metres).
    pub position: f64,
    /// Turn error about the vertical (radians).
    pub yaw: f64,
}

impl Default for PoseNoise {
    /// 2 mm and 1°: a calibrated RGB-D tabletop pose estimator's typical error.
    fn default() -> Self {
        PoseNoise {
            position: 0.002,
            yaw: 1f64.to_radians(),
        }
    }
}

impl PoseNoise {
    /// No noise: the planner sees the true world.
    pub const NONE: PoseNoise = PoseNoise {
        position: 0.0,
        yaw: 0.0,
    };
}

/// The world as perceived in the trial seeded `seed`: `truth` with every movable object's pose
/// disturbed by `noise`. Deterministic per seed; objects are drawn in the world's order.
pub(crate) fn perceive(truth: &World, noise: &PoseNoise, seed: u64) -> World {
    // Its own ChaCha stream: independent of the placement drawn from the same seed.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    let gauss = |sigma: f64| Normal::new(0.0, sigma).ok();
    let (position, yaw) = (gauss(noise.position), gauss(noise.yaw));
    let mut seen = truth.clone();
    for o in seen.objects.iter_mut().filter(|o| o.movable) {
        let mut draw = |d: &Option<Normal<f64>>| d.as_ref().map_or(0.0, |d| d.sample(&mut rng));
        let (dx, dy, turn) = (draw(&position), draw(&position), draw(&yaw));
        o.pose.translation =
            Translation3::from(o.pose.translation.vector + Vector3::new(dx, dy, 0.0));
        o.pose.rotation =
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn) * o.pose.rotation;
    }
    seen
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::position_distance;

    fn world() -> World {
        akl_scene::builtin::task("pick_place")
            .unwrap()
            .unwrap()
            .world
    }

    #[test]
    fn perception_moves_only_movable_objects_in_the_plane_reproducibly() {
        let truth = world();
        let seen = perceive(&truth, &PoseNoise::default(), 3);
        assert_eq!(seen, perceive(&truth, &PoseNoise::default(), 3));
        assert_ne!(seen, perceive(&truth, &PoseNoise::default(), 4));
        for (a, b) in truth.objects.iter().zip(&seen.objects) {
            let d = b.pose.translation.vector - a.pose.translation.vector;
            assert_eq!(d.z, 0.0);
            if a.movable {
                assert!(d.norm() > 0.0 && d.norm() < 0.02, "{} moved {d:?}", a.name);
            } else {
                assert_eq!(a.pose, b.pose);
            }
        }
    }

    #[test]
    fn the_spread_matches_the_deviation_and_none_is_exact() {
        let truth = world();
        let noise = PoseNoise {
            position: 0.002,
            yaw: 0.0,
        };
        let n = 2000;
        let mean_square: f64 = (0..n)
            .map(|s| {
                let seen = perceive(&truth, &noise, s);
                let at = |w: &World| w.object("block_a").unwrap().pose.translation.vector;
                let d = at(&seen) - at(&truth);
                d.x * d.x
            })
            .sum::<f64>()
            / n as f64;
        assert!(
            (mean_square.sqrt() - 0.002).abs() < 2e-4,
            "{}",
            mean_square.sqrt()
        );
        let exact = perceive(&truth, &PoseNoise::NONE, 9);
        for (a, b) in truth.objects.iter().zip(&exact.objects) {
            assert!(position_distance(&a.pose, &b.pose) == 0.0);
        }
    }
}
