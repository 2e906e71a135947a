//! The proof that a stretch of a joint-space edge is free: how far the bodies move along it
//! ([`Sweep`]) against the clearances found at a check ([`Proof`]).

use super::model::RobotCollision;

/// Work space of an edge check: the joint motion of the stretch being proved free and the
/// motion bounds derived from it.
pub(super) struct Sweep {
    /// How far each arm joint turns or slides from the check to either end of the stretch.
    pub(super) half: Vec<f64>,
    /// For each chain k of the model, `bounds[offsets[k] + m]` bounds how far any point of
    /// its element moves through the joints `m..` of the chain (0 past the last one).
    pub(super) bounds: Vec<f64>,
}

impl Sweep {
    pub(super) fn new(model: &RobotCollision, dof: usize) -> Sweep {
        Sweep {
            half: vec![0.0; dof],
            bounds: vec![0.0; model.offsets.last().copied().unwrap_or(0)],
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
    pub(super) fn moved(&self, k: usize, from: usize) -> f64 {
        self.sweep.bounds[self.offsets[k] + from]
    }

    /// The clearance beyond which an element moving `moved` with `slack` to spare shortens
    /// nothing: a distance query need not be exact past it.
    pub(super) fn useful_clearance(&self, moved: f64, slack: f64) -> f64 {
        moved * self.fraction - slack
    }

    /// Whether a clearance larger than 0 would shorten nothing: an element moving `moved`
    /// with `slack` to spare is already within the current fraction.
    pub(super) fn settled(&self, moved: f64, slack: f64) -> bool {
        self.useful_clearance(moved, slack) <= 0.0
    }

    /// [`Proof::settled`] for the clearance `slack + √distance_sq`, without the square root
    /// (checks take it for every element and object whose boxes are apart).
    pub(super) fn settled_sq(&self, moved: f64, slack: f64, distance_sq: f64) -> bool {
        let useful = self.useful_clearance(moved, slack);
        useful <= 0.0 || distance_sq >= useful * useful
    }

    /// Limits the fraction to what `slack` (clearance plus half the margin) allows an element
    /// moving up to `moved` over the whole stretch.
    pub(super) fn limit(&mut self, moved: f64, slack: f64) {
        if moved * self.fraction > slack {
            self.fraction = slack / moved;
        }
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
            moved in 0.0..0.5f64,
            slack in -0.05..0.05f64,
            distance in 0.0..0.3f64,
            fraction in 0.0..1.0f64,
        ) {
            let sweep = Sweep { half: Vec::new(), bounds: Vec::new() };
            let proof = Proof { sweep: &sweep, offsets: &[], fraction };
            let exact = proof.settled(moved, slack + distance);
            let squared = proof.settled_sq(moved, slack, distance * distance);
            // Equal up to the rounding of a square; never settled where the distance is short.
            let useful = proof.useful_clearance(moved, slack);
            if (distance - useful).abs() > 1e-12 {
                prop_assert_eq!(exact, squared);
            }
        }
    }
}
