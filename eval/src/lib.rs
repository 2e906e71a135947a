//! The thesis's user study (chapter 4), simulated.
//!
//! A fixed population of simulated teachers ([`population`]) calibrates, then teaches each
//! built-in task with each method — AKL, KD and mACL — in a counterbalanced order, and every
//! learned spec is scored against the task's ground truth with the measures of §4.2.

pub mod plots;
pub mod population;
pub mod records;
pub mod shards;
pub mod study;
pub mod summary;
