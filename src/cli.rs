//! Command-line arguments.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Teach a robot arm a multistep task from one demonstration, as the least restrictive
/// sequence of Task Space Region keyframes, and check the learned spec before it runs.
#[derive(Debug, Parser)]
#[command(name = "akl", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// List and inspect tasks (built-in or from a task file).
    #[command(subcommand)]
    Task(TaskCommand),
    /// Validate and inspect task specifications (spec.json).
    #[command(subcommand)]
    Spec(SpecCommand),
    /// Inspect the robot model: joints and limits, forward and inverse kinematics.
    #[command(subcommand)]
    Robot(RobotCommand),
    /// Plan a spec for the robot in a task's world: one timed joint trajectory.
    ///
    /// Each keyframe is grounded on the objects' poses; free segments are planned with
    /// RRT-Connect and shortcut, move_in_line segments keep the tool centre point on the
    /// straight line, grasps and releases are approached along the tool axis. Prints per
    /// segment its kind, duration and planning time.
    ///
    /// Exit codes: 0 planned; 2 bad input (a missing or invalid spec file, an unknown task, a
    /// spec naming objects the task does not have, a bad robot folder); 1 the spec cannot be
    /// planned (the message names the keyframe or segment and why: unreachable, no
    /// collision-free IK solution, planning budget exhausted, the line leaves the workspace or
    /// collides) or the output cannot be written.
    Plan(PlanArgs),
}

/// `--robot DIR`, shared by the commands that use a robot.
#[derive(Debug, Clone, clap::Args)]
pub struct RobotArg {
    /// Robot folder (robot.toml and its URDF); the built-in Franka Panda if omitted.
    #[arg(long, value_name = "DIR")]
    pub robot: Option<PathBuf>,
}

/// `akl robot ...`
#[derive(Debug, Subcommand)]
pub enum RobotCommand {
    /// Show the robot: joints, limits, ready pose, gripper, links and collision margins.
    Info {
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Forward kinematics: the TCP and flange poses (robot base frame) of a configuration.
    ///
    /// Exits with 2 if the joint list is malformed, has the wrong length or leaves the limits.
    Fk {
        /// Joint positions in radians, comma-separated, base to tip (e.g. 0,-0.785,0,-2.356,0,1.571,0.785).
        #[arg(long, value_name = "Q1,...,Qn", allow_hyphen_values = true)]
        joints: String,
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Inverse kinematics: the configuration nearest a seed that puts the TCP at a pose.
    ///
    /// The pose is in the robot base frame. Exits with 1 and says "unreachable" if no
    /// configuration within the joint limits reaches it; with 2 if the input is malformed.
    Ik {
        /// Target TCP pose: position (m) and unit quaternion, comma-separated.
        #[arg(long, value_name = "X,Y,Z,QX,QY,QZ,QW", allow_hyphen_values = true)]
        pose: String,
        /// Seed configuration (default: the ready pose).
        #[arg(long, value_name = "Q1,...,Qn", allow_hyphen_values = true)]
        seed_joints: Option<String>,
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

/// `akl plan SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The spec file to plan.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec is planned in.
    #[arg(long)]
    pub task: String,
    /// Seed of the planner's random choices (same seed, same plan).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the full plan (timed trajectory and gripper events) as JSON to this file.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the per-segment summary as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `akl task ...`
#[derive(Debug, Subcommand)]
pub enum TaskCommand {
    /// List the built-in tasks.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show a task: its objects, randomization ranges, goals and teaching steps.
    Show {
        /// A built-in task name (see `akl task list`) or the path of a task file.
        task: String,
        /// Print the task file as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// `akl spec ...`
#[derive(Debug, Subcommand)]
pub enum SpecCommand {
    /// Validate a spec and summarize it: keyframes, kinds, references and constraints.
    ///
    /// References are checked against the objects of the task named in the spec when it is a
    /// built-in task, or of the task given with --task. Exits with 2 if the spec is invalid.
    Check {
        /// The spec file.
        file: PathBuf,
        /// Task (built-in name or task file) whose objects the references must name.
        #[arg(long)]
        task: Option<String>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a spec's keyframes as a table (or JSON).
    Show {
        /// The spec file.
        file: PathBuf,
        /// Print the spec as JSON.
        #[arg(long)]
        json: bool,
    },
}
