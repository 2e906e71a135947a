//! Specs judged by execution in the simulation (thesis §3.2, Theorem 3.2.3, and beyond it).
//!
//! - [`validation`]: a deployment gate. The spec must pass its randomized trials and be least
//!   restrictive: [`ablation`] executes it without each keyframe and without each
//!   `move_in_line` on the same seeds, and a removal that still passes every trial is not
//!   essential. With the demonstration it was learned from, [`answers`] reports the teacher's
//!   answers the simulation contradicts.
//! - [`relax`]: each keyframe's TSR widened, axis by axis, as far as the trials allow, the
//!   result re-verified on fresh seeds before it is returned.
//! - [`compare`]: one row per spec (keyframes, lines, bits of freedom, planning, execution,
//!   validation verdict).
//!
//! Every trial here is planned with goals drawn at random across each keyframe's TSR
//! ([`trials::verifying`]): a spec claims that any pose of its regions will do, and only a
//! planner that goes across them tests that claim.

pub mod ablation;
pub mod answers;
pub mod compare;
pub mod error;
pub mod relax;
pub mod trials;
pub mod validation;

pub use error::ValidateError;
pub use trials::{Outcome, Trials};
pub use validation::{validate, ValidateOptions, Validation, Verdict};
