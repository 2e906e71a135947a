//! The subcommands that show the robot, the tasks and specs.

use super::shared::RobotArg;
use clap::Subcommand;
use std::path::PathBuf;

/// `akl robot ...`
#[derive(Debug, Subcommand)]
pub(crate) enum RobotCommand {
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

/// `akl task ...`
#[derive(Debug, Subcommand)]
pub(crate) enum TaskCommand {
    /// List the built-in tasks.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show a task: its objects, every randomization range and rigid group, the layout rules,
    /// the fixed relations (groundings no randomized trial can tell apart), its goals, its
    /// teaching steps and its ground truth.
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
pub(crate) enum SpecCommand {
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
