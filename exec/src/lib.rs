//! Verified execution of AKL task specs: the spec is planned on a perceived world and its plan
//! simulated in the true one (rapier3d), and every check reads the simulated bodies.
//!
//! A [`batch::Batch`] runs a spec's seeded trials in parallel ([`run_trial`] is one of them) and
//! gives a [`report::BatchReport`]; [`merge`] joins the reports of a run's shards ([`Shard`]) and
//! resumes interrupted runs ([`Interrupt`]), and [`junit`] writes a report as JUnit XML. The
//! simulation itself ([`SimWorld`], [`simulate`] and what it measures, [`Observations`]) is
//! public for tests and benchmarks that drive it directly; [`check_settles`] tells whether a
//! task's world stands still untouched.

mod arm;
pub mod batch;
mod checks;
mod contacts;
mod convert;
mod error;
mod exact_depth;
mod grasp;
mod interrupt;
mod junit;
pub mod merge;
mod options;
mod perception;
pub mod report;
mod settle;
mod shard;
mod simulate;
mod timeline;
mod trace;
mod trial;
mod visual;
mod world;

pub use arm::Drives;
pub use contacts::{Collision, ContactLimits, ContactLog, ContactPoint, Extreme};
pub use error::ExecError;
pub use grasp::{GraspLimits, GraspMeasure};
pub use interrupt::Interrupt;
pub use junit::{junit, Suite};
pub use options::{ExecOptions, Setup};
pub use perception::PoseNoise;
pub use settle::{check_settles, Unsettled, SETTLE_SECONDS, SETTLE_TOLERANCE};
pub use shard::{Shard, ShardError, ShardRequest};
pub use simulate::{simulate, GraspEvent, KeyframeReach, LinePath, Observations, ReleaseEvent};
pub use timeline::{Frame, Timeline};
pub use trace::TRACE_RATE;
pub use trial::{run_trial, trial_world};
pub use world::{Physics, SimWorld};
