//! Verified execution of AKL task specs: the spec is planned on a perceived world and its plan
//! simulated in the true one (rapier3d), and every check reads the simulated bodies.

pub mod arm;
pub mod batch;
pub mod checks;
pub mod contacts;
pub mod convert;
pub mod error;
pub mod grasp;
pub mod interrupt;
pub mod junit;
pub mod merge;
pub mod options;
pub mod perception;
pub mod report;
pub mod settle;
pub mod shard;
pub mod simulate;
pub mod timeline;
pub mod trace;
pub mod trial;
pub mod visual;
pub mod world;

pub use options::{ExecOptions, Setup};
pub use timeline::{Frame, Timeline};
