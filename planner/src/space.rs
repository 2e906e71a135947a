//! The joint space a segment is planned in: limits, the collision context (gripper opening,
//! held object, allowed contacts) and edge validity (all along the edge, see `collision`).

use crate::collision::{Checker, Held, Hit};
use crate::contact_rules::Allowances;
use rand::distributions::{Distribution, Uniform};
use rand::Rng;

/// Configurations and straight joint-space edges of one planning context.
pub struct Space<'a> {
    /// The checker (robot, collision model, scene).
    pub checker: &'a Checker<'a>,
    /// Gripper opening during the segment.
    pub width: f64,
    /// The object held during the segment, if any.
    pub held: Option<&'a Held>,
    /// Contacts allowed during the segment.
    pub allow: &'a Allowances,
}

impl Space<'_> {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.checker.robot().dof()
    }

    /// The first collision of `q`, if any.
    pub fn check(&self, q: &[f64]) -> Option<Hit> {
        self.checker.check(q, self.width, self.held, self.allow)
    }

    /// Whether `q` is collision-free and within the limits.
    #[cfg(test)]
    pub(crate) fn valid(&self, q: &[f64]) -> bool {
        self.check(q).is_none()
    }

    /// The first collision on the straight edge from `a` to `b`, if any.
    pub(crate) fn edge(&self, a: &[f64], b: &[f64]) -> Option<Hit> {
        self.checker.edge(a, b, self.width, self.held, self.allow)
    }

    /// [`Space::edge`] for an edge whose start `a` is already known to be valid (the end of
    /// the edge before it, in a chain of edges): `a` is not checked again.
    pub(crate) fn edge_from_valid(&self, a: &[f64], b: &[f64]) -> Option<Hit> {
        self.checker
            .screened_edge(a, b, self.width, self.held, self.allow, 0)
    }

    /// Whether the straight edge from `a` to `b` is collision-free.
    pub fn edge_valid(&self, a: &[f64], b: &[f64]) -> bool {
        self.edge(a, b).is_none()
    }

    /// Whether the straight edge from `a` to `b` is collision-free, after a screen of
    /// `points` of its points (see [`Checker::screened_edge`]) that rejects it on a collision
    /// found there. `a` must already be known to be valid (a search's node): it is not
    /// checked again.
    pub(crate) fn screened_edge_valid(&self, a: &[f64], b: &[f64], points: usize) -> bool {
        self.checker
            .screened_edge(a, b, self.width, self.held, self.allow, points)
            .is_none()
    }

    /// Draws configurations uniformly within the joint limits ([`Sampler`]).
    pub fn sampler(&self) -> Sampler {
        Sampler::within(self.checker.robot().joint_limits())
    }
}

/// Configurations drawn uniformly within the joint limits: for each joint exactly the value
/// `rng.gen_range(lo..=hi)` draws, whose distribution rand makes afresh on every call (a
/// division and a loop, 3 % of a search's instructions); made once here.
pub struct Sampler {
    joints: Vec<Uniform<f64>>,
}

impl Sampler {
    /// Draws each joint within its `[lower, upper]` limits.
    fn within(limits: &[[f64; 2]]) -> Sampler {
        Sampler {
            joints: limits
                .iter()
                .map(|&[lo, hi]| Uniform::new_inclusive(lo, hi))
                .collect(),
        }
    }

    /// Writes a configuration drawn from `rng` into `out`.
    pub fn fill<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        for (v, joint) in out.iter_mut().zip(&self.joints) {
            *v = joint.sample(rng);
        }
    }
}

/// Euclidean distance in joint space.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Total joint-space length of a path.
pub(crate) fn path_length(path: &[Vec<f64>]) -> f64 {
    path.windows(2).map(|w| distance(&w[0], &w[1])).sum()
}

/// The point a fraction `t` of the way from `a` to `b`.
pub(crate) fn lerp(a: &[f64], b: &[f64], t: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect()
}

#[cfg(test)]
mod tests {
    use super::Sampler;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    proptest! {
        /// The sampler draws what `gen_range` over each joint's limits draws, bit for bit, so
        /// that a search's samples do not depend on which of the two made them.
        #[test]
        fn draws_are_gen_range_draws(
            seed: u64,
            limits in prop::collection::vec((-4.0..4.0f64, 0.0..6.0f64), 1..9),
        ) {
            let limits: Vec<[f64; 2]> = limits.iter().map(|&(lo, w)| [lo, lo + w]).collect();
            let sampler = Sampler::within(&limits);
            let (mut a, mut b) = (ChaCha8Rng::seed_from_u64(seed), ChaCha8Rng::seed_from_u64(seed));
            let mut q = vec![0.0; limits.len()];
            for _ in 0..20 {
                sampler.fill(&mut a, &mut q);
                for (v, [lo, hi]) in q.iter().zip(&limits) {
                    let expected: f64 = b.gen_range(*lo..=*hi);
                    prop_assert_eq!(v.to_bits(), expected.to_bits());
                    prop_assert!(*lo <= *v && *v <= *hi);
                }
            }
        }
    }
}
