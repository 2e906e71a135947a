//! Options several commands share: the robot, the task fit, speed, trials and the gate.

use std::path::PathBuf;

/// `--speed-scale S`, shared by the commands that plan.
#[derive(Debug, Clone, Copy, clap::Args)]
pub(crate) struct SpeedArg {
    /// How fast the arm may move, in (0, 1]: joint velocity limits times S, accelerations
    /// times S² (MoveIt's scaling factors S and S²), fingers at S times their speed, the pause
    /// after the gripper 1/S as long: the whole plan takes 1/S as long. 1 (the default) moves
    /// as fast as the robot allows. Recorded in reports.
    #[arg(long, value_name = "S", default_value_t = 1.0, value_parser = parse_speed_scale)]
    pub speed_scale: f64,
}

fn parse_speed_scale(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1.0 => Ok(s),
        _ => Err(format!("expected a number in (0, 1], got `{text}`")),
    }
}

/// `--any-task`, shared by the commands that run a spec in a task.
#[derive(Debug, Clone, Copy, clap::Args)]
pub(crate) struct AnyTaskArg {
    /// Run the spec even though its `task` field names another task than --task (refused by
    /// default: a spec given another task's world is almost always a mistake).
    #[arg(long)]
    pub any_task: bool,
}

/// `--robot DIR`, shared by the commands that use a robot.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct RobotArg {
    /// Robot folder (robot.toml and its URDF); the built-in Franka Panda if omitted.
    #[arg(long, value_name = "DIR")]
    pub robot: Option<PathBuf>,
    /// Where a ROS package the URDF's `package://` meshes name lies (repeatable); looked up
    /// before the robot folder's `[packages]` and `ROS_PACKAGE_PATH`.
    #[arg(long, value_name = "NAME=DIR", requires = "robot")]
    pub package_path: Vec<akl_planner::PackagePath>,
}

/// Trial settings shared by `akl validate`, `relax` and `compare`.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct TrialArgs {
    /// Trials run in parallel (default: the number of cores).
    #[arg(long, value_name = "J")]
    pub jobs: Option<usize>,
    /// Perception error of the movable objects' poses (as `akl execute --pose-noise`).
    #[arg(long, value_name = "MM,DEG", default_value = "2,1", value_parser = parse_pose_noise)]
    pub pose_noise: PoseNoiseArg,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// What the deployment gate asks (shared by `akl validate`, `relax` and `compare`).
#[derive(Debug, Clone, Copy, clap::Args)]
pub(crate) struct GateArgs {
    /// The success probability the spec must be shown to reach.
    #[arg(long, value_name = "P", default_value_t = 0.99)]
    pub min_success: f64,
    /// The confidence each look of the sequential test shows it at.
    #[arg(long, value_name = "C", default_value_t = 0.95)]
    pub confidence: f64,
    /// Trials after which the gate stops undecided (default 2,000; for `akl relax`, whose
    /// gates pass only what has no failure, 299).
    #[arg(long, value_name = "N", alias = "randomize")]
    pub max_trials: Option<usize>,
}

/// `--pose-noise MM,DEG`: standard deviations of perceived position (mm) and yaw (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PoseNoiseArg {
    /// Millimetres.
    pub millimetres: f64,
    /// Degrees.
    pub degrees: f64,
}

pub(super) fn parse_pose_noise(text: &str) -> Result<PoseNoiseArg, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [mm, deg] = parts[..] else {
        return Err(format!("expected MM,DEG (e.g. 2,1), got `{text}`"));
    };
    let number = |s: &str, what: &str| -> Result<f64, String> {
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
            _ => Err(format!("{what} must be a number >= 0, got `{s}`")),
        }
    };
    Ok(PoseNoiseArg {
        millimetres: number(mm, "millimetres")?,
        degrees: number(deg, "degrees")?,
    })
}
