//! Specs judged by execution in the simulation (thesis §3.2, Theorem 3.2.3, and beyond it).
//! Every decision here is made by the deployment gate of [`akl_stats::gate`] on randomized
//! trials in seed order ([`trials::run_gated`]), so a verdict says at what confidence it holds
//! and does not flip with the number of trials asked for.
//!
//! - [`validation`]: the deployment gate. The spec must pass the gate and be least
//!   restrictive: [`ablation`] gates it without each keyframe and without each `move_in_line`
//!   on the same seeds, and a removal that passes the gate is not essential. With the
//!   demonstration it was learned from, [`answers`] reports the teacher's answers the
//!   simulation contradicts.
//! - [`relax`]: each keyframe's TSR widened axis by axis after a cheap screening against the
//!   spec's own failures, and everything screening kept gated at once on fresh seeds; a gate
//!   that fails is blamed on the keyframes whose widening, undone, passes its failed trials.
//! - [`grounding`]: every keyframe re-grounded on every other object, judged by the same gate:
//!   does the randomization tell the spec's reference apart?
//! - [`compare`]: one row per spec (keyframes, lines, bits of freedom, planning, execution,
//!   validation verdict).
//!
//! Every trial here is planned with goals drawn at random across each keyframe's TSR
//! ([`trials::verifying`]): a spec claims that any pose of its regions will do, and only a
//! planner that goes across them tests that claim.

pub mod ablation;
pub mod answers;
pub mod compare;
mod error;
pub mod grounding;
pub mod relax;
pub mod trials;
pub mod validation;

pub use error::ValidateError;
pub use trials::{Outcome, Trials};
pub use validation::{validate, ValidateOptions, Validation, Verdict};
