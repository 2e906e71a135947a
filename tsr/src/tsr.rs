//! Task Space Regions (Berenson, Srinivasa & Kuffner 2011).
//!
//! A TSR is a set of end-effector poses: `T0_e = T0_w · Tw(c) · Tw_e` for every displacement
//! `c = (x, y, z, roll, pitch, yaw)` inside the bounds `bw`, where `Tw(c)` is expressed in the
//! frame w whose world pose is `t0_w`, and `tw_e` is the end-effector offset from that frame.

use crate::error::BoundsError;
use crate::pose::{serde_pose, Pose};
use crate::rpy::{folded_rpy, rotation_from_rpy, rpy_from_rotation, wrap_angle};
use nalgebra::{Isometry3, Translation3};
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Metres of position error that one radian of rotation error counts as in [`Tsr::distance`].
///
/// 0.1 m/rad: the Panda's tool centre point is about 0.1 m from its flange, so turning the hand
/// by θ about the tool centre moves the wrist by about 0.1·θ; a rotation error then weighs what
/// it displaces at the wrist.
pub const ROTATION_WEIGHT: f64 = 0.1;

/// Slack on every bound when testing membership, absorbing floating-point round-off of
/// composing and decomposing transforms (poses built from in-bound displacements must test
/// inside, even on a bound of zero width).
pub(crate) const BOUND_SLACK: f64 = 1e-9;

/// Names of the six TSR coordinates, in order.
pub const COORDINATE_NAMES: [&str; 6] = ["x", "y", "z", "roll", "pitch", "yaw"];

/// The 6×2 bounds `[min, max]` on x, y, z (metres) and roll, pitch, yaw (radians) in frame w.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Bounds(pub [[f64; 2]; 6]);

impl Bounds {
    /// Bounds of ± `position` metres on each axis and ± `rotation` radians about each axis.
    pub fn symmetric(position: f64, rotation: f64) -> Self {
        let p = [-position, position];
        let r = [-rotation, rotation];
        Bounds([p, p, p, r, r, r])
    }

    /// Bounds that admit exactly one pose (the nominal one).
    pub fn point() -> Self {
        Bounds([[0.0; 2]; 6])
    }

    /// Checks that every bound is finite and ordered; the error names the coordinate.
    pub fn validate(&self) -> Result<(), BoundsError> {
        for (&coordinate, [lo, hi]) in COORDINATE_NAMES.iter().zip(self.0) {
            if !lo.is_finite() || !hi.is_finite() {
                return Err(BoundsError::NotFinite { coordinate, lo, hi });
            }
            if lo > hi {
                return Err(BoundsError::Unordered { coordinate, lo, hi });
            }
        }
        Ok(())
    }

    /// Whether the zero displacement (the nominal pose) lies inside.
    pub fn contains_zero(&self) -> bool {
        self.0.iter().all(|[lo, hi]| *lo <= 0.0 && *hi >= 0.0)
    }
}

/// A Task Space Region: the poses `t0_w · Tw(c) · tw_e` for displacements `c` within `bw`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tsr {
    /// World pose of the frame w the region is expressed in (a reference object's pose).
    #[serde(with = "serde_pose")]
    pub t0_w: Pose,
    /// End-effector offset from the displaced frame w.
    #[serde(with = "serde_pose")]
    pub tw_e: Pose,
    /// Bounds on the displacement in frame w.
    pub bw: Bounds,
}

impl Tsr {
    /// A region from its three parts.
    pub fn new(t0_w: Pose, tw_e: Pose, bw: Bounds) -> Self {
        Tsr { t0_w, tw_e, bw }
    }

    /// The same region expressed relative to a frame w that now sits at `t0_w`.
    pub fn rebased(&self, t0_w: Pose) -> Self {
        Tsr {
            t0_w,
            tw_e: self.tw_e,
            bw: self.bw,
        }
    }

    /// The pose at zero displacement, `t0_w · tw_e`.
    pub fn nominal(&self) -> Pose {
        self.t0_w * self.tw_e
    }

    /// The pose at displacement `c` (x, y, z, roll, pitch, yaw), whether or not `c` is in bounds.
    pub fn pose_at(&self, c: &[f64; 6]) -> Pose {
        self.t0_w * displacement_transform(c) * self.tw_e
    }

    /// The displacement coordinates of `pose` in this region's frame; among the equivalent
    /// roll-pitch-yaw triples (2π wraps, the pitch fold, and at gimbal lock the whole family
    /// with the same rotation) the one nearest the bounds is returned.
    pub fn coordinates(&self, pose: &Pose) -> [f64; 6] {
        let tw = self.t0_w.inverse() * pose * self.tw_e.inverse();
        let t = tw.translation.vector;
        let rpy = nearest_rpy(rpy_from_rotation(&tw.rotation), &self.bw);
        [t.x, t.y, t.z, rpy[0], rpy[1], rpy[2]]
    }

    /// How far each coordinate of `pose` lies outside its bound (signed, 0 inside).
    pub fn displacement(&self, pose: &Pose) -> [f64; 6] {
        let c = self.coordinates(pose);
        let mut d = [0.0; 6];
        for i in 0..6 {
            d[i] = outside(c[i], self.bw.0[i]);
        }
        d
    }

    /// Distance from `pose` to the region: the norm of the displacement, with rotation weighted
    /// by [`ROTATION_WEIGHT`] metres per radian. Zero exactly when [`Tsr::contains`] holds.
    pub fn distance(&self, pose: &Pose) -> f64 {
        weighted_norm(&self.displacement(pose))
    }

    /// Whether `pose` lies in the region (up to 1e-9 of round-off).
    pub fn contains(&self, pose: &Pose) -> bool {
        self.displacement(pose).iter().all(|v| *v == 0.0)
    }

    /// The pose of the region nearest to `pose` in displacement coordinates.
    pub fn closest(&self, pose: &Pose) -> Pose {
        let mut c = self.coordinates(pose);
        for (v, [lo, hi]) in c.iter_mut().zip(self.bw.0) {
            *v = v.clamp(lo, hi);
        }
        self.pose_at(&c)
    }

    /// Displacement coordinates drawn uniformly within the bounds.
    pub fn sample_coordinates<R: Rng + ?Sized>(&self, rng: &mut R) -> [f64; 6] {
        let mut c = [0.0; 6];
        for (v, [lo, hi]) in c.iter_mut().zip(self.bw.0) {
            *v = if hi > lo { rng.gen_range(lo..=hi) } else { lo };
        }
        c
    }

    /// A pose drawn from the region (coordinates uniform within the bounds).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Pose {
        self.pose_at(&self.sample_coordinates(rng))
    }
}

/// Norm of a 6-vector of (position, rotation) differences with rotation weighted by
/// [`ROTATION_WEIGHT`].
pub(crate) fn weighted_norm(d: &[f64; 6]) -> f64 {
    let p = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let r = d[3] * d[3] + d[4] * d[4] + d[5] * d[5];
    (p + ROTATION_WEIGHT * ROTATION_WEIGHT * r).sqrt()
}

fn displacement_transform(c: &[f64; 6]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(c[0], c[1], c[2]),
        rotation_from_rpy([c[3], c[4], c[5]]),
    )
}

/// Signed amount by which `v` lies outside `[lo, hi]` widened by the slack; 0 inside.
fn outside(v: f64, [lo, hi]: [f64; 2]) -> f64 {
    if v < lo - BOUND_SLACK {
        v - lo
    } else if v > hi + BOUND_SLACK {
        v - hi
    } else {
        0.0
    }
}

/// The angle equivalent to `a` (modulo 2π) nearest the interval `[lo, hi]`.
fn wrap_into(a: f64, [lo, hi]: [f64; 2]) -> f64 {
    if hi - lo >= 2.0 * PI {
        return lo + (a - lo).rem_euclid(2.0 * PI);
    }
    let centre = 0.5 * (lo + hi);
    centre + wrap_angle(a - centre)
}

/// How far an rpy triple is from the angular bounds, once each angle is wrapped nearest them.
fn rpy_violation(rpy: [f64; 3], bw: &Bounds) -> ([f64; 3], f64) {
    let mut wrapped = [0.0; 3];
    let mut sq = 0.0;
    for i in 0..3 {
        wrapped[i] = wrap_into(rpy[i], bw.0[3 + i]);
        let o = outside(wrapped[i], bw.0[3 + i]);
        sq += o * o;
    }
    (wrapped, sq)
}

/// Below this |cos(pitch)| roll and yaw are no longer separable: only their sum or difference
/// is determined, and shifting both along the free direction leaves the rotation unchanged.
const GIMBAL_LOCK_COS: f64 = 1e-9;

fn nearest_rpy(rpy: [f64; 3], bw: &Bounds) -> [f64; 3] {
    let mut candidates = vec![rpy, folded_rpy(rpy)];
    if rpy[1].cos().abs() < GIMBAL_LOCK_COS {
        // At pitch = +π/2 the rotation depends on roll − yaw, at −π/2 on roll + yaw; the
        // nearest member of that family has roll or yaw on one of its bounds.
        let s = if rpy[1] > 0.0 { 1.0 } else { -1.0 };
        let [[rlo, rhi], [ylo, yhi]] = [bw.0[3], bw.0[5]];
        for t in [
            rlo - rpy[0],
            rhi - rpy[0],
            s * (ylo - rpy[2]),
            s * (yhi - rpy[2]),
        ] {
            candidates.push([rpy[0] + t, rpy[1], rpy[2] + s * t]);
        }
    }
    candidates
        .into_iter()
        .map(|c| rpy_violation(c, bw))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(wrapped, _)| wrapped)
        .unwrap_or(rpy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::{pose_from_xyz_rpy, position_distance, rotation_distance};
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn arb_pose() -> impl Strategy<Value = Pose> {
        (
            prop::array::uniform3(-1.0..1.0f64),
            prop::array::uniform3(-PI..PI),
        )
            .prop_map(|(p, r)| pose_from_xyz_rpy(p, [r[0], r[1] * 0.5, r[2]]))
    }

    fn arb_bounds() -> impl Strategy<Value = Bounds> {
        (
            prop::array::uniform3((-0.2..0.2f64, 0.0..0.3f64)),
            prop::array::uniform3((-PI..PI, 0.0..2.5f64)),
        )
            .prop_map(|(p, r)| {
                let mut b = [[0.0; 2]; 6];
                for i in 0..3 {
                    b[i] = [p[i].0, p[i].0 + p[i].1];
                    b[3 + i] = [r[i].0, r[i].0 + r[i].1];
                }
                b[4] = [
                    b[4][0].clamp(-PI / 2.0, PI / 2.0),
                    b[4][1].clamp(-PI / 2.0, PI / 2.0),
                ];
                Bounds(b)
            })
    }

    fn arb_tsr() -> impl Strategy<Value = Tsr> {
        (arb_pose(), arb_pose(), arb_bounds()).prop_map(|(a, b, bw)| Tsr::new(a, b, bw))
    }

    proptest! {
        #[test]
        fn a_sample_lies_in_its_tsr(tsr in arb_tsr(), seed in any::<u64>()) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let pose = tsr.sample(&mut rng);
            prop_assert!(tsr.contains(&pose), "displacement {:?}", tsr.displacement(&pose));
            prop_assert_eq!(tsr.distance(&pose), 0.0);
        }

        #[test]
        fn distance_is_zero_exactly_on_contains(tsr in arb_tsr(), pose in arb_pose()) {
            prop_assert_eq!(tsr.contains(&pose), tsr.distance(&pose) == 0.0);
        }

        #[test]
        fn closest_lies_in_the_tsr_and_is_no_farther_than_any_member(
            tsr in arb_tsr(), pose in arb_pose(), seed in any::<u64>()
        ) {
            let closest = tsr.closest(&pose);
            prop_assert!(tsr.contains(&closest), "displacement {:?}", tsr.displacement(&closest));
            prop_assert!(tsr.distance(&closest) <= tsr.distance(&pose));
            let c = tsr.coordinates(&pose);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for _ in 0..8 {
                let s = tsr.sample_coordinates(&mut rng);
                let mut diff = [0.0; 6];
                for i in 0..6 { diff[i] = c[i] - s[i]; }
                prop_assert!(tsr.distance(&pose) <= weighted_norm(&diff) + 1e-12);
            }
        }

        #[test]
        fn a_pose_inside_is_its_own_closest(tsr in arb_tsr(), seed in any::<u64>()) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let pose = tsr.sample(&mut rng);
            let closest = tsr.closest(&pose);
            prop_assert!(position_distance(&pose, &closest) < 1e-9);
            prop_assert!(rotation_distance(&pose, &closest) < 1e-7);
        }

        #[test]
        fn coordinates_reproduce_the_pose(tsr in arb_tsr(), pose in arb_pose()) {
            let back = tsr.pose_at(&tsr.coordinates(&pose));
            prop_assert!(position_distance(&pose, &back) < 1e-9);
            prop_assert!(rotation_distance(&pose, &back) < 1e-7);
        }

        #[test]
        fn a_tsr_moves_with_its_frame(tsr in arb_tsr(), frame in arb_pose(), seed in any::<u64>()) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let pose = tsr.sample(&mut rng);
            let moved = tsr.rebased(frame * tsr.t0_w);
            prop_assert!(moved.contains(&(frame * pose)));
        }
    }

    #[test]
    fn yaw_is_wrapped_to_meet_bounds_across_the_seam() {
        let tsr = Tsr::new(
            Pose::identity(),
            Pose::identity(),
            Bounds([[0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2], [3.0, 3.3]]),
        );
        let pose = pose_from_xyz_rpy([0.0; 3], [0.0, 0.0, 3.25 - 2.0 * PI]);
        assert!(tsr.contains(&pose));
    }

    #[test]
    fn the_pitch_fold_is_used_when_it_is_nearer() {
        // roll = π, pitch = π − 0.2, yaw = π is the same rotation as (0, 0.2, 0).
        let tsr = Tsr::new(
            Pose::identity(),
            Pose::identity(),
            Bounds([
                [0.0; 2],
                [0.0; 2],
                [0.0; 2],
                [-0.1, 0.1],
                [0.1, 0.3],
                [-0.1, 0.1],
            ]),
        );
        let pose = pose_from_xyz_rpy([0.0; 3], [PI, PI - 0.2, PI]);
        assert!(tsr.contains(&pose), "{:?}", tsr.displacement(&pose));
    }

    #[test]
    fn gimbal_lock_uses_the_free_roll_yaw_direction() {
        // At pitch = π/2 only roll − yaw matters: (0.5, π/2, 0.5) equals (0, π/2, 0).
        let bw = Bounds([
            [0.0; 2],
            [0.0; 2],
            [0.0; 2],
            [0.4, 0.6],
            [-2.0, 2.0],
            [0.4, 0.6],
        ]);
        let tsr = Tsr::new(Pose::identity(), Pose::identity(), bw);
        let pose = pose_from_xyz_rpy([0.0; 3], [0.0, PI / 2.0, 0.0]);
        assert!(tsr.contains(&pose), "{:?}", tsr.displacement(&pose));
    }

    #[test]
    fn distance_weights_rotation_by_the_documented_factor() {
        let tsr = Tsr::new(Pose::identity(), Pose::identity(), Bounds::point());
        let pose = pose_from_xyz_rpy([0.03, 0.0, 0.04], [0.0, 0.0, 0.0]);
        assert!((tsr.distance(&pose) - 0.05).abs() < 1e-12);
        let turned = pose_from_xyz_rpy([0.0; 3], [0.0, 0.0, 0.5]);
        assert!((tsr.distance(&turned) - 0.5 * ROTATION_WEIGHT).abs() < 1e-12);
    }

    #[test]
    fn bounds_validation_names_the_coordinate() {
        let mut b = Bounds::symmetric(0.01, 0.1);
        b.0[4] = [0.2, -0.2];
        assert_eq!(
            b.validate(),
            Err(BoundsError::Unordered {
                coordinate: "pitch",
                lo: 0.2,
                hi: -0.2
            })
        );
        b.0[4] = [f64::NAN, 0.0];
        assert!(b.validate().unwrap_err().to_string().contains("not finite"));
    }
}
