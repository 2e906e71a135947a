//! Collision check: the contact verdicts gathered during the run (see [`crate::contacts`]).

use crate::contacts::Collision;
use crate::report::{Cause, Failure};

/// A failure for each pair that collided, at its first offending contact.
pub(crate) fn check(collisions: &[Collision]) -> Vec<Failure> {
    collisions
        .iter()
        .map(|c| {
            Failure::new(Cause::Collision, c.describe())
                .at(c.keyframe)
                .at_time(c.t)
        })
        .collect()
}
