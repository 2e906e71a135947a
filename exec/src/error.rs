//! Typed errors of execution. A trial that fails its checks is not an error (it is reported);
//! these are the reasons a batch cannot run at all, or its outputs cannot be written.

use std::path::PathBuf;

/// Why execution could not run or could not write its outputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExecError {
    /// The robot could not be loaded.
    #[error("robot: {0}")]
    Robot(#[from] akl_planner::RobotError),
    /// The robot cannot be built in the simulation (no fixed base, no two-finger gripper, a
    /// joint that is neither an arm nor a finger joint).
    #[error("robot model: {0}")]
    RobotModel(String),
    /// The spec does not fit the task (e.g. a reference object the task does not have).
    #[error("spec: {0}")]
    Spec(#[from] akl_tsr::SpecError),
    /// The task's objects could not be placed within their randomization ranges.
    #[error("task: {0}")]
    Scene(#[from] akl_scene::SceneError),
    /// The shard asked for cannot run (more shards than trials).
    #[error("{0}")]
    Shard(#[from] crate::shard::ShardError),
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// An output file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
}
