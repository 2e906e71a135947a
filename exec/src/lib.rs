//! Verified execution of AKL task specs in rapier3d.

pub mod arm;
pub mod convert;
pub mod world;
