//! Planning benchmarks on problem files shared with other planners: every problem solved
//! from its start to its goal configuration by the project's RRT-Connect under the
//! project's collision model, with records another planner's runner writes too, so that
//! both are read by one analysis and compared on the problems both call valid.

mod problems;
mod run;
mod summary;

pub use problems::{Obstacle, ObstacleShape, Problem, ProblemFile, ProblemFileError};
pub use run::{run_problem, BenchSettings, ProblemOutcome, ProblemRecord, RunRecord};
pub use summary::{compare, summarize, SetComparison, SetSummary, Times, ALL_SETS};
