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
    /// Is a configuration in collision, with what, and how close is each obstacle?
    ///
    /// Uses the planner's own collision model and rules: the grown hulls that hold the
    /// robot's meshes, grown by the robot's margins (or by --margin). Exits with 0 when the
    /// configuration is free, 1 when it is in collision, 2 on bad input.
    Check(RobotCheckArgs),
    /// Write a robot folder guessed from a stock URDF, and print what was guessed.
    ///
    /// Finds the arm (root, joints, flange), the gripper (two prismatic fingers, or a knuckle
    /// with `<mimic>` joints), the TCP between the fingertip pads (adding a link to the folder's
    /// copy of the URDF when none lies there), limits from the URDF, a ready pose pointing
    /// down in front of the base, and the link pairs never checked (adjacent, and never or
    /// always meeting over random configurations). Review robot.toml before use (fields:
    /// robots/README.md). Exits with 2 on a bad URDF, a mesh that cannot be found, an output
    /// folder that already holds robot.toml, or a written folder that does not load (e.g. a
    /// gripper the simulation cannot drive: the folder is kept for editing).
    Init(RobotInitArgs),
    /// Compute the robot's self-collision tables ahead and write them to a file.
    ///
    /// Checks fill the tables of link pairs that one or two joints move against each other
    /// node by node as they reach them (about 3 µs a node). A robot folder's
    /// `self_tables.bin`, which this command writes, gives every process all of them at
    /// start. Values are stored under a fingerprint of the robot, its margins and the code
    /// that computes them: a table whose fingerprint differs ignores them and fills itself.
    /// The built-in Panda's are embedded (robots/panda/self_tables.bin). Exits with 2 on bad
    /// input.
    Tables {
        #[command(flatten)]
        robot: RobotArg,
        /// The file to write (default: the robot folder's self_tables.bin; required for the
        /// built-in Panda).
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
        /// Threads that compute nodes (default: the number of cores).
        #[arg(long, value_name = "J")]
        jobs: Option<usize>,
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

/// `akl robot init`.
#[derive(Debug, clap::Args)]
pub(crate) struct RobotInitArgs {
    /// The URDF (expanded: `xacro robot.urdf.xacro > robot.urdf`).
    pub urdf: PathBuf,
    /// Where a ROS package the URDF's `package://` meshes name lies (repeatable); written
    /// into the folder's `[packages]`.
    #[arg(long, value_name = "NAME=DIR")]
    pub package_path: Vec<akl_planner::PackagePath>,
    /// The robot folder to write (must not hold a robot.toml yet).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub output: PathBuf,
    /// Random configurations drawn to find link pairs that never meet.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub samples: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `akl robot check`.
#[derive(Debug, clap::Args)]
pub(crate) struct RobotCheckArgs {
    /// Joint positions in radians, comma-separated, base to tip.
    #[arg(long, value_name = "Q1,...,Qn", allow_hyphen_values = true)]
    pub joints: String,
    /// Gripper opening (metres; default: fully open).
    #[arg(long, value_name = "WIDTH", allow_negative_numbers = true)]
    pub gripper: Option<f64>,
    /// Check against a task's world (built-in name or task file), in the task file's layout.
    #[arg(long, value_name = "TASK", conflicts_with = "obstacles")]
    pub task: Option<String>,
    /// Check against obstacles: a JSON file `{"objects": [...]}` in a task file's
    /// world-object format, poses in the robot base frame.
    #[arg(long, value_name = "FILE")]
    pub obstacles: Option<PathBuf>,
    /// Clearance kept by every link, instead of the robot's margins (0 = the geometry alone).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub margin: Option<f64>,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}
