//! Verified execution of AKL task specs in rapier3d.

pub mod arm;
pub mod batch;
pub mod contacts;
pub mod convert;
pub mod error;
pub mod grasp;
pub mod report;
pub mod trace;
pub mod trial;
pub mod verify;
pub mod world;
