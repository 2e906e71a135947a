//! The checks of a trial, one per file: each reads what the simulated run measured
//! ([`crate::simulate::Observations`]) and turns it into its report entries and failures. None of them reads
//! the plan's own poses: the plan only says when a keyframe or a line happens.

pub mod collision;
pub mod goals;
pub mod grasp;
pub mod keyframe;
pub mod line;
pub mod release;
pub mod slip;
