//! Cheap geometry that culls exact tests: bodies placed as segments, their bounding boxes
//! and the distance between segments.

use super::model::Body;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use wide::f64x4;

/// A capsule-like body in world coordinates: a segment and a radius.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Placed {
    pub(super) pose: Pose,
    pub(super) a: Vector3<f64>,
    pub(super) b: Vector3<f64>,
}

#[inline(always)]
pub(super) fn placed(body: &Body, link_pose: &Pose) -> Placed {
    let pose = link_pose * body.local;
    // The segment's ends: the centre ± half the segment along the element's z axis, the
    // quaternion's third rotation column written out: 2–4 % of a whole check faster than
    // nalgebra's `rotation * Vector3::z()` (two alternated collision-bench runs).
    let [x, y, z, w] = [
        pose.rotation.i,
        pose.rotation.j,
        pose.rotation.k,
        pose.rotation.w,
    ];
    let axis = Vector3::new(
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    );
    let centre = pose.translation.vector;
    let half = body.half_segment * axis;
    Placed {
        pose,
        a: centre - half,
        b: centre + half,
    }
}

/// The world-axis-aligned box around `p` grown by `r`: its lower and upper corners.
pub(super) fn bounding_box(p: &Placed, r: f64) -> [Vector3<f64>; 2] {
    let grow = Vector3::repeat(r);
    [p.a.inf(&p.b) - grow, p.a.sup(&p.b) + grow]
}

/// Four objects' world-axis-aligned boxes side by side: a check measures every element's box
/// against every object's, four objects at a time in the lanes of `f64x4` vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct BoxLanes {
    min: [f64x4; 3],
    max: [f64x4; 3],
}

/// Objects whose boxes a [`BoxLanes`] holds.
pub(super) const BOX_LANES: usize = 4;

impl BoxLanes {
    /// The boxes (lower and upper corners) of `boxes`, four at a time; the spare lanes of the
    /// last group hold an empty box, infinitely far from every box.
    pub(super) fn of(boxes: &[[Vector3<f64>; 2]]) -> Vec<BoxLanes> {
        boxes
            .chunks(BOX_LANES)
            .map(|group| {
                let corner = |c: usize, i: usize, empty: f64| {
                    f64x4::new(std::array::from_fn(|l| {
                        group.get(l).map_or(empty, |b| b[c][i])
                    }))
                };
                BoxLanes {
                    min: std::array::from_fn(|i| corner(0, i, f64::INFINITY)),
                    max: std::array::from_fn(|i| corner(1, i, f64::NEG_INFINITY)),
                }
            })
            .collect()
    }

    /// The squared gap between the box `b` (lower and upper corners) and each of the four
    /// (0 where they meet, infinite for an empty lane): [`box_gap_sq`]'s figure to the last
    /// bit, each lane taking its operations in the same order.
    #[inline(always)]
    pub(super) fn gaps_sq(&self, b: &[Vector3<f64>; 2]) -> [f64; BOX_LANES] {
        let axis = |i: usize| {
            let below = f64x4::splat(b[0][i]) - self.max[i];
            let above = self.min[i] - f64x4::splat(b[1][i]);
            let d = below.fast_max(above).fast_max(f64x4::ZERO);
            d * d
        };
        (axis(0) + axis(1) + axis(2)).to_array()
    }

    /// The lanes whose boxes meet the box `b` (lower and upper corners), as bits (bit l for
    /// lane l): exactly those whose [`box_gap_sq`] is 0, an empty lane never.
    #[inline(always)]
    pub(super) fn meeting(&self, b: &[Vector3<f64>; 2]) -> u32 {
        let apart = |i: usize| {
            f64x4::splat(b[0][i]).simd_gt(self.max[i]) | self.min[i].simd_gt(f64x4::splat(b[1][i]))
        };
        !(apart(0) | apart(1) | apart(2)).to_bitmask() & LANE_BITS
    }

    /// The squared gaps of [`BoxLanes::gaps_sq`], and as bits the lanes whose boxes meet the
    /// box `b` or are less than `useful` from it (`useful` > 0): the objects a proof must look
    /// at closer when a clearance of `useful` would settle its stretch.
    #[inline(always)]
    pub(super) fn within(&self, b: &[Vector3<f64>; 2], useful: f64) -> (u32, [f64; BOX_LANES]) {
        let gaps = self.gaps_sq(b);
        let reach_sq = useful * useful;
        // With nothing (or, its square underflowing, next to nothing) to gain, only the
        // boxes that meet.
        if useful <= 0.0 || reach_sq == 0.0 {
            return (self.meeting(b), gaps);
        }
        let near = f64x4::new(gaps).simd_lt(f64x4::splat(reach_sq));
        (near.to_bitmask() & LANE_BITS, gaps)
    }
}

/// The bits of a [`BoxLanes`]'s four lanes.
const LANE_BITS: u32 = (1 << BOX_LANES) - 1;

/// The lanes whose bits are set in `bits` (as [`BoxLanes::meeting`] and [`BoxLanes::within`]
/// give them), lowest first.
#[inline(always)]
pub(super) fn set_lanes(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let lane = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            lane
        })
    })
}

/// Squared distance between two world-axis-aligned boxes (0 when they overlap).
pub(super) fn box_gap_sq(a: &[Vector3<f64>; 2], min: &Vector3<f64>, max: &Vector3<f64>) -> f64 {
    (a[0] - max)
        .sup(&(min - a[1]))
        .sup(&Vector3::zeros())
        .norm_squared()
}

/// Squared distance between segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision
/// Detection, §5.1.9), for the cheap rejection of far link pairs.
pub(super) fn segment_distance_sq(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> f64 {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t);
    if a <= 1e-12 && e <= 1e-12 {
        return r.dot(&r);
    }
    if a <= 1e-12 {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= 1e-12 {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s0 = if denom > 1e-12 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    let c1 = p1 + d1 * s;
    let c2 = p2 + d2 * t;
    (c1 - c2).norm_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::RobotCollision;
    use crate::robot::Robot;
    use akl_tsr::nalgebra::{Point3, Translation3, UnitQuaternion};

    /// The segment's ends are the element's pose applied to (0, 0, ±half segment).
    #[test]
    fn placed_ends_are_the_posed_segment_ends() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        for (k, body) in model.bodies.iter().enumerate() {
            let f = k as f64;
            let link = Pose::from_parts(
                Translation3::new(0.1 * f, -0.2, 0.3),
                UnitQuaternion::from_euler_angles(0.3 * f, 1.0 - 0.2 * f, 0.7),
            );
            let p = placed(body, &link);
            let pose = link * body.local;
            let a = (pose * Point3::new(0.0, 0.0, -body.half_segment)).coords;
            let b = (pose * Point3::new(0.0, 0.0, body.half_segment)).coords;
            assert!((p.a - a).norm() < 1e-12 && (p.b - b).norm() < 1e-12, "{k}");
        }
    }

    proptest::proptest! {
        /// Four boxes side by side give each one's squared gap exactly as `box_gap_sq` does,
        /// touching faces included (corners on a coarse grid, so that faces often meet); they
        /// meet the element exactly where that gap is 0, and are within reach of a proof
        /// exactly where the gap does not settle it; the spare lanes of a short group are
        /// infinitely far and never meet.
        #[test]
        fn box_lanes_give_each_gap_exactly(
            element in proptest::array::uniform6(-3i8..4),
            objects in proptest::collection::vec(proptest::array::uniform6(-3i8..4), 1..7),
            scale in 0.01..1.0f64,
        ) {
            let corners = |c: [i8; 6]| {
                let v = |i: usize| f64::from(c[i]) * scale;
                let (x, y) = (Vector3::new(v(0), v(1), v(2)), Vector3::new(v(3), v(4), v(5)));
                [x.inf(&y), x.sup(&y)]
            };
            let element = corners(element);
            let boxes: Vec<[Vector3<f64>; 2]> = objects.into_iter().map(corners).collect();
            let lanes = BoxLanes::of(&boxes);
            proptest::prop_assert_eq!(lanes.len(), boxes.len().div_ceil(BOX_LANES));
            for (k, group) in lanes.iter().enumerate() {
                let gaps = group.gaps_sq(&element);
                for (l, gap) in gaps.iter().enumerate() {
                    match boxes.get(k * BOX_LANES + l) {
                        Some(b) => proptest::prop_assert_eq!(
                            gap.to_bits(),
                            box_gap_sq(&element, &b[0], &b[1]).to_bits()
                        ),
                        None => proptest::prop_assert_eq!(*gap, f64::INFINITY),
                    }
                    let bit = |mask: u32| mask & (1 << l) != 0;
                    let real = k * BOX_LANES + l < boxes.len();
                    proptest::prop_assert_eq!(bit(group.meeting(&element)), real && *gap == 0.0);
                    // A proof skips a box whose gap settles the stretch (`Proof::settled_sq`).
                    let settled = |useful: f64| *gap > 0.0 && (useful <= 0.0 || *gap >= useful * useful);
                    for useful in [-0.1, 0.0, 1e-200, 0.5 * scale, scale, 3.0 * scale] {
                        let (mask, gaps) = group.within(&element, useful);
                        proptest::prop_assert_eq!(gaps, group.gaps_sq(&element));
                        proptest::prop_assert_eq!(bit(mask), real && !settled(useful));
                    }
                }
            }
        }
    }
}
