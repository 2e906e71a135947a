//! The subcommands that measure the planner on shared problem sets.

use super::shared::RobotArg;
use clap::Subcommand;
use std::path::PathBuf;

/// `akl bench ...`
#[derive(Debug, Subcommand)]
pub(crate) enum BenchCommand {
    /// Plan every problem of a shared problem file from its start to its goal configuration.
    ///
    /// The file holds named scenes of boxes, cylinders and spheres and problems posed in them
    /// (the format other planners' runners read; README "Planning benchmarks"; the
    /// MotionBenchMaker problems are in benches/problems/mbm_panda.json). Each problem whose
    /// start and goal are valid under the planner's collision model and margins is solved
    /// --seeds times by RRT-Connect, one problem at a time on one core. Where only the hand
    /// touches an object at the start or goal (a goal that grasps it), the hand may touch that
    /// object throughout.
    ///
    /// Prints per set: problems, valid problems, runs solved, median and 95th-percentile
    /// planning time; with --against, the same on the problems both planners call valid, and
    /// the ratio of the times. --json prints one record per problem with the fields the peer
    /// runner (run_vamp.py) writes. Exits with 0 when every run solved its problem, 1 when a
    /// run exhausted its budget, 2 on bad input.
    Planning(BenchPlanningArgs),
}

/// `akl bench planning`
#[derive(Debug, clap::Args)]
pub(crate) struct BenchPlanningArgs {
    /// The problem file (JSON).
    #[arg(value_name = "PROBLEMS.json")]
    pub problems: PathBuf,
    /// Runs per problem; run s uses seed s.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub seeds: u64,
    /// Samples RRT-Connect draws before it gives up on a run (those the dynamic domain turns
    /// away count; the default is VAMP's).
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    pub max_iterations: usize,
    /// Plan without the dynamic domain (samples far from a node that met an obstacle are
    /// not drawn again), to measure what it gives.
    #[arg(long)]
    pub no_dynamic_domain: bool,
    /// Let the two trees take turns instead of always growing the smaller one.
    #[arg(long)]
    pub no_balance: bool,
    /// Keep every step at the full range instead of halving a node's step for every 1,000
    /// extensions from it that met an obstacle, to measure what the halving gives.
    #[arg(long)]
    pub no_step_halving: bool,
    /// Only the problems of these sets (repeatable).
    #[arg(long, value_name = "NAME")]
    pub set: Vec<String>,
    /// Another planner's records of the same file (a JSON array as run_vamp.py writes it):
    /// compare on the problems both call valid.
    #[arg(long, value_name = "RECORDS.json")]
    pub against: Option<PathBuf>,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the records as JSON (one per problem) instead of the tables.
    #[arg(long)]
    pub json: bool,
}
