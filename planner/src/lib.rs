//! Robot model, inverse kinematics, collision checking and motion planning for AKL specs.
//!
//! A [`Robot`] is loaded from a folder holding a URDF and a `robot.toml` (the Panda is built
//! in). Its forward kinematics come from the k tree, compiled into flat arrays for speed; its
//! inverse kinematics are analytic for the Panda and damped least squares otherwise.
//! Collision checking uses parry3d shapes built from the URDF collision elements and the
//! scene's objects. [`plan_task`] turns a task spec into one timed joint trajectory ([`Plan`]),
//! the quickest of the whole-spec candidates its budget allows ([`PlanBudget`], `search`).

pub mod benchmark;
pub mod check;
pub mod collision;
pub mod config;
pub mod contact_rules;
pub mod enclosure;
pub mod error;
pub mod fk;
pub mod flexibility;
pub mod geometry;
pub mod goal;
pub mod hand;
pub mod ik;
pub mod line;
pub mod meshes;
pub mod options;
pub mod parry_convert;
pub mod plan;
pub mod robot;
pub mod robot_init;
pub mod rrt;
pub mod search;
pub mod shortcut;
pub mod space;
pub mod squeeze;
pub mod task;
pub mod timing;
pub mod urdf_load;

pub use config::RobotConfig;
pub use error::{
    ConfigError, GripperError, IkError, JointsError, PandaIkError, PlanError, RobotError, UrdfError,
};
pub use geometry::{Geometry, LinkShape, ShapeRole};
pub use options::{PlanBudget, PlanOptions};
pub use plan::{GripperAction, GripperEvent, LinePoses, Plan, Segment, SegmentKind};
pub use robot::Robot;
pub use search::{plan_best, plan_task, BestPlan, CandidateOutcome};
