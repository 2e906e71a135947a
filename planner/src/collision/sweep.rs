//! The proof that a stretch of a joint-space edge is free: how far the bodies move along it
//! ([`Sweep`], [`Motion`]) against the clearances found at a check ([`Proof`]).

use super::model::RobotCollision;
use crate::parry_convert::Slab;
use akl_tsr::nalgebra::Vector3;
use std::ops::Add;

/// A bound on how far a point moves over a stretch, kept as a function of the share f of
/// the stretch (0 ≤ f ≤ 1) that is taken: at most `linear`·f + `higher`·f².
///
/// Turning a joint moves a point by its distance from the axis times the turn, and that
/// distance grows with what the joints beyond move the point: the bound is a polynomial in f
/// with non-negative coefficients, whose first-order part is `linear` and whose terms of
/// second order and above, at most their sum times f² for f ≤ 1, are `higher`. Taking a
/// share of a stretch shrinks its second-order part quadratically, so a proof that shortens
/// the stretch to fit a clearance proves more than the whole stretch's bound scaled down.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Motion {
    /// The first-order part: the sum of each joint's turn times the point's distance from
    /// its axis at the check (and each slide).
    pub(super) linear: f64,
    /// The terms of second order and above at f = 1.
    pub(super) higher: f64,
}

impl Motion {
    #[cfg(test)]
    /// The bound over the whole stretch.
    pub(super) fn whole(self) -> f64 {
        self.linear + self.higher
    }

    /// The bound over the share `f` (0 ≤ f ≤ 1) of the stretch.
    pub(super) fn at(self, f: f64) -> f64 {
        f * (self.linear + f * self.higher)
    }

    /// The largest share of the stretch over which the motion stays within `slack` (may
    /// exceed 1; 0 if `slack` is not positive).
    pub(super) fn share_within(self, slack: f64) -> f64 {
        if slack <= 0.0 {
            return 0.0;
        }
        // The positive root of higher·f² + linear·f − slack, in the form that keeps its
        // precision when `higher` is small.
        let root = (self.linear * self.linear + 4.0 * self.higher * slack).sqrt();
        let denominator = self.linear + root;
        if denominator > 0.0 {
            2.0 * slack / denominator
        } else {
            f64::INFINITY
        }
    }

    #[cfg(test)]
    /// The motion of a point carried further by `turn` (radians, times the joint's scale) of
    /// a revolute joint whose axis is `reach` from the point at the check.
    pub(super) fn turned(self, reach: f64, turn: f64) -> Motion {
        Motion {
            linear: self.linear + reach * turn,
            higher: self.higher + turn * (self.linear + self.higher),
        }
    }

    #[cfg(test)]
    /// The motion of a point carried further by a slide of `distance` metres.
    pub(super) fn slid(self, distance: f64) -> Motion {
        Motion {
            linear: self.linear + distance,
            higher: self.higher,
        }
    }
}

impl Add for Motion {
    type Output = Motion;
    fn add(self, other: Motion) -> Motion {
        Motion {
            linear: self.linear + other.linear,
            higher: self.higher + other.higher,
        }
    }
}

/// The first-order motion of a chain's element at a check, as vectors, and what its motion
/// can stray from it over the stretch: a bound on the element's motion along one direction
/// ([`Carried::along`]), which is all that can close a gap found along that direction.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Carried {
    /// The velocity of the element's centre (metres per share of the stretch).
    pub(super) velocity: Vector3<f64>,
    /// The element's turning rate (radians per share of the stretch).
    pub(super) spin: Vector3<f64>,
    /// How far the element's points lie from its centre, at most.
    pub(super) extent: f64,
    /// The slides' lengths, summed.
    pub(super) slid: f64,
    /// How far the motion can stray from the first-order one over the whole stretch.
    pub(super) stray: f64,
}

impl Carried {
    /// A bound on how far any point of the element moves along the unit vector `n` (either
    /// way) over a share of the stretch: its centre's velocity along `n`, plus what turning
    /// moves a point `extent` from the centre along `n` (at most the turning rate across `n`
    /// times `extent`), plus the slides and the stray, which may point any way.
    pub(super) fn along(&self, n: &Vector3<f64>) -> Motion {
        Motion {
            linear: self.velocity.dot(n).abs()
                + self.spin.cross(n).norm() * self.extent
                + self.slid,
            higher: self.stray,
        }
    }
}

/// Work space of an edge check: the joint motion of the stretch being proved free and the
/// motion bounds derived from it.
pub(super) struct Sweep {
    /// The joint motion from the check to one end of the stretch (to the other it is the
    /// opposite): how far each arm joint turns or slides, with its sign.
    pub(super) step: Vec<f64>,
    /// For each chain k of the model, `bounds[offsets[k] + m]` bounds how far any point of
    /// its element moves through the joints `m..` of the chain (0 past the last one).
    pub(super) bounds: Vec<Motion>,
    /// For each chain k, `carried[offsets[k]]` is its element's first-order motion through
    /// the whole chain (the other slots are unused).
    pub(super) carried: Vec<Carried>,
}

impl Sweep {
    pub(super) fn new(model: &RobotCollision, dof: usize) -> Sweep {
        let slots = model.offsets.last().copied().unwrap_or(0);
        Sweep {
            step: vec![0.0; dof],
            bounds: vec![Motion::default(); slots],
            carried: vec![Carried::default(); slots],
        }
    }
}

/// Tracks, during one check, how much of a stretch its clearances prove free: the fraction
/// of the stretch (up to 1) over which no element moves further than its clearance plus
/// half its margin.
pub(super) struct Proof<'s> {
    pub(super) sweep: &'s Sweep,
    pub(super) offsets: &'s [usize],
    pub(super) fraction: f64,
}

impl Proof<'_> {
    /// Bound on how far chain `k` moves through its joints from `from` on.
    pub(super) fn moved(&self, k: usize, from: usize) -> Motion {
        self.sweep.bounds[self.offsets[k] + from]
    }

    /// Bound on how far any point of chain `k`'s element moves along the unit vector `n`.
    pub(super) fn moved_along(&self, k: usize, n: &Vector3<f64>) -> Motion {
        self.sweep.carried[self.offsets[k]].along(n)
    }

    /// The share of the stretch over which chain `k`'s element keeps within `slack` beyond
    /// the far side of `slab`: motion along the slab's normal within its width plus `slack`.
    pub(super) fn share_across(&self, k: usize, slack: f64, slab: &Slab) -> f64 {
        self.moved_along(k, &slab.normal)
            .share_within(slack + slab.width)
    }

    /// The clearance beyond which an element moving `moved` with `slack` to spare shortens
    /// nothing: a distance query need not be exact past it.
    pub(super) fn useful_clearance(&self, moved: Motion, slack: f64) -> f64 {
        moved.at(self.fraction) - slack
    }

    /// Whether a clearance larger than 0 would shorten nothing: an element moving `moved`
    /// with `slack` to spare is already within the current fraction.
    pub(super) fn settled(&self, moved: Motion, slack: f64) -> bool {
        self.useful_clearance(moved, slack) <= 0.0
    }

    /// [`Proof::settled`] for the clearance `slack + √distance_sq`, without the square root
    /// (checks take it for every element and object whose boxes are apart).
    pub(super) fn settled_sq(&self, moved: Motion, slack: f64, distance_sq: f64) -> bool {
        let useful = self.useful_clearance(moved, slack);
        useful <= 0.0 || distance_sq >= useful * useful
    }

    /// Limits the fraction to what `slack` (clearance plus half the margin) allows an element
    /// moving up to `moved` over the whole stretch.
    pub(super) fn limit(&mut self, moved: Motion, slack: f64) {
        if moved.at(self.fraction) > slack {
            self.fraction = moved.share_within(slack).min(self.fraction);
        }
    }

    /// Limits the fraction to the largest share that one element's clearance proves:
    /// `distance` (plus `slack`) against its motion in any direction, the width of the slab
    /// `across` (plus `slack`) against its motion along the slab's normal, or `proved`, a
    /// share cheaper bounds proved already. `chain` is the element's, `moved` its motion.
    pub(super) fn limit_by_clearance(
        &mut self,
        chain: usize,
        moved: Motion,
        slack: f64,
        distance: f64,
        across: Option<Slab>,
        proved: f64,
    ) {
        if moved.at(self.fraction) <= slack + distance {
            return;
        }
        let mut share = moved.share_within(slack + distance).max(proved);
        if let Some(slab) = across.filter(|_| share < self.fraction) {
            share = share.max(self.share_across(chain, slack, &slab));
        }
        self.fraction = self.fraction.min(share);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Settling on a squared distance decides as settling on the distance itself: a pair
        /// whose clearance would shorten the stretch is never skipped.
        #[test]
        fn settling_on_a_squared_distance_decides_as_on_the_distance(
            linear in 0.0..0.5f64,
            higher in 0.0..0.5f64,
            slack in -0.05..0.05f64,
            distance in 0.0..0.3f64,
            fraction in 0.0..1.0f64,
        ) {
            let moved = Motion { linear, higher };
            let sweep = Sweep { step: Vec::new(), bounds: Vec::new(), carried: Vec::new() };
            let proof = Proof { sweep: &sweep, offsets: &[], fraction };
            let exact = proof.settled(moved, slack + distance);
            let squared = proof.settled_sq(moved, slack, distance * distance);
            // Equal up to the rounding of a square; never settled where the distance is short.
            let useful = proof.useful_clearance(moved, slack);
            if (distance - useful).abs() > 1e-12 {
                prop_assert_eq!(exact, squared);
            }
        }

        /// Over any share of a stretch, a chain's motion (each joint turning a point at most
        /// its distance from the axis, grown by what the joints beyond move it, times the
        /// joint's turn over that share) stays within the bound kept for the whole stretch.
        #[test]
        fn a_share_of_a_stretch_moves_within_the_bound(
            joints in prop::collection::vec((0.0..1.0f64, 0.0..1.5f64, any::<bool>()), 0..9),
            f in 0.0..=1.0f64,
        ) {
            let mut motion = Motion::default();
            let mut share = 0.0;
            for &(reach, turn, slides) in joints.iter().rev() {
                let t = f * turn;
                if slides {
                    motion = motion.slid(turn);
                    share += t;
                } else {
                    motion = motion.turned(reach, turn);
                    share += (reach + share) * t;
                }
            }
            prop_assert!(share <= motion.at(f) * (1.0 + 1e-12) + 1e-15);
            if f == 1.0 {
                prop_assert!((share - motion.whole()).abs() <= 1e-12 * share.max(1.0));
            }
        }

        /// The share a clearance proves keeps the motion within it, and is never less than
        /// the whole stretch's bound scaled down (the proof before this bound).
        #[test]
        fn a_limited_share_keeps_within_the_slack(
            linear in 0.0..2.0f64,
            higher in 0.0..2.0f64,
            slack in 1e-4..0.2f64,
        ) {
            let moved = Motion { linear, higher };
            let sweep = Sweep { step: Vec::new(), bounds: Vec::new(), carried: Vec::new() };
            let mut proof = Proof { sweep: &sweep, offsets: &[], fraction: 1.0 };
            proof.limit(moved, slack);
            prop_assert!(moved.at(proof.fraction) <= slack * (1.0 + 1e-12));
            prop_assert!(proof.fraction >= (slack / moved.whole()).min(1.0) * (1.0 - 1e-12));
            prop_assert!(proof.fraction <= 1.0);
        }
    }
}
