//! The checks of a trial, one per file: each reads what the simulated run measured
//! ([`crate::simulate::Observations`]) and turns it into its report entries and failures. None of them reads
//! the plan's own poses: the plan only says when a keyframe or a line happens.

pub(crate) mod collision;
pub(crate) mod goals;
pub(crate) mod grasp;
pub(crate) mod keyframe;
pub(crate) mod line;
pub(crate) mod release;
pub(crate) mod slip;
