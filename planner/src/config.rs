//! `robot.toml`: what the planner needs to know about a robot beyond its URDF.

use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// The parsed `robot.toml` of a robot folder (see `robots/panda/robot.toml` for the fields).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// Short robot name.
    pub name: String,
    /// File name of the URDF, relative to the robot folder.
    pub urdf: String,
    /// Link whose pose keyframes constrain: the tool centre point.
    pub tcp_link: String,
    /// The flange link (reported alongside the TCP).
    pub flange_link: String,
    /// Configuration every plan starts from, in arm joint order.
    pub ready: Vec<f64>,
    /// Joint velocity limits (rad/s or m/s), in arm joint order.
    pub velocity_limits: Vec<f64>,
    /// Joint acceleration limits (rad/s² or m/s²), in arm joint order.
    pub acceleration_limits: Vec<f64>,
    /// Which inverse kinematics solver to use.
    pub ik: IkConfig,
    /// The gripper.
    pub gripper: GripperConfig,
    /// Collision margins and exclusions.
    pub collision: CollisionConfig,
    /// ROS packages the URDF's `package://` meshes name, each with its folder relative to
    /// the robot folder (e.g. `franka_description = "."`).
    #[serde(default)]
    pub packages: std::collections::BTreeMap<String, String>,
    /// Where the robot stands: the pose of the URDF's root link in the task's robot base
    /// frame; `None` stands it at the task's robot base.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount: Option<MountConfig>,
}

/// The `[mount]` table: a pose as a URDF `<origin>` gives one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountConfig {
    /// Position (metres).
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Orientation: roll, pitch, yaw (radians), fixed axes x, y, z.
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl MountConfig {
    /// The pose of the URDF's root link in the task's robot base frame.
    pub(crate) fn pose(&self) -> akl_tsr::Pose {
        akl_tsr::pose::pose_from_xyz_rpy(self.xyz, self.rpy)
    }
}

/// The `[ik]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IkConfig {
    /// The solver to use.
    pub solver: IkSolverKind,
}

/// The inverse kinematics solvers a robot can ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IkSolverKind {
    /// Analytic Panda solver (joint 7 searched); the URDF must have the Panda's joint structure.
    Panda,
    /// Damped least squares with joint limits and random restarts; works for any arm.
    Dls,
    /// Damped least squares and Levenberg–Marquardt racing with random restarts, in the
    /// manner of TRAC-IK; works for any arm.
    Trac,
}

/// The `[gripper]` table: a symmetric parallel gripper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GripperConfig {
    /// Finger joints; each moves `width / joints.len()`.
    pub joints: Vec<String>,
    /// Opening width when open (metres).
    pub open_width: f64,
    /// Finger speed (m/s).
    pub speed: f64,
    /// Links that touch grasped objects (hand and fingers).
    pub hand_links: Vec<String>,
}

/// The `[collision]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionConfig {
    /// Clearance between arm links and the world (metres).
    pub arm_margin: f64,
    /// Clearance between hand links and the world (metres).
    pub hand_margin: f64,
    /// Clearance between a held object and fixed objects (metres); from movable objects and
    /// the arm it keeps the larger of this and `hand_margin`.
    pub held_margin: f64,
    /// Clearance between link pairs that are checked against each other (metres).
    pub self_margin: f64,
    /// Links not checked against the object the robot is mounted on.
    #[serde(default)]
    pub mount_links: Vec<String>,
    /// Link pairs never checked against each other.
    #[serde(default)]
    pub allowed_pairs: Vec<[String; 2]>,
}

impl RobotConfig {
    /// Parses `robot.toml` text; the error carries the TOML parser's line and column.
    pub fn from_toml(text: &str) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Toml(e.to_string().trim_end().to_string()))
    }

    /// Checks the numbers the TOML shape cannot express (finite, positive where needed).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let positive = |field: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ConfigError::NotPositive {
                    field: field.to_string(),
                    value,
                })
            }
        };
        for (i, v) in self.velocity_limits.iter().enumerate() {
            positive(&format!("velocity_limits[{i}]"), *v)?;
        }
        for (i, v) in self.acceleration_limits.iter().enumerate() {
            positive(&format!("acceleration_limits[{i}]"), *v)?;
        }
        if let Some(v) = self.ready.iter().find(|v| !v.is_finite()) {
            return Err(ConfigError::ReadyNotFinite(*v));
        }
        if let Some(m) = &self.mount {
            let values = m.xyz.iter().chain(&m.rpy);
            if let Some(v) = values.copied().find(|v| !v.is_finite()) {
                return Err(ConfigError::MountNotFinite(v));
            }
        }
        positive("gripper.open_width", self.gripper.open_width)?;
        positive("gripper.speed", self.gripper.speed)?;
        let c = &self.collision;
        for (name, v) in [
            ("collision.arm_margin", c.arm_margin),
            ("collision.hand_margin", c.hand_margin),
            ("collision.held_margin", c.held_margin),
            ("collision.self_margin", c.self_margin),
        ] {
            positive(name, v)?;
        }
        Ok(())
    }
}
