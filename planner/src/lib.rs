//! Robot model, inverse kinematics, collision checking and motion planning for AKL specs.
//!
//! A [`Robot`] is loaded from a folder holding a URDF and a `robot.toml` (the Panda is built
//! in). Its forward kinematics come from the k tree, compiled into flat arrays for speed; its
//! inverse kinematics are analytic for the Panda and damped least squares otherwise.
//! Collision checking uses parry3d shapes built from the URDF collision elements and the
//! scene's objects. [`plan_task`] turns a task spec into one timed joint trajectory ([`Plan`]),
//! the quickest of the whole-spec candidates its budget allows ([`PlanBudget`], [`plan_best`]).
//!
//! At the root: the robot and its configuration, the planning entry points, their options and
//! results, and the errors; what the simulation shares with the planner so that both judge a
//! grasp and a line alike (the hand's pads, the squeeze, [`distance_to_segment`], and
//! [`cylinder_axis`]: the turn between AKL's cylinders and parry's and rapier's). Five modules are namespaces of their own: [`collision`] (the
//! checker, its scene and the robot's collision model), [`contact_rules`] (which contacts a
//! step may make, read by the planner and the simulation alike), [`flexibility`] (the bits of
//! freedom of a spec), [`robot_init`] (a robot folder guessed from a stock URDF) and
//! [`benchmark`] (planning benchmark problems, runs and summaries).

pub mod benchmark;
#[cfg(test)]
mod check;
pub mod collision;
mod config;
pub mod contact_rules;
mod enclosure;
mod error;
mod fk;
pub mod flexibility;
mod geometry;
mod goal;
mod hand;
mod ik;
mod line;
mod meshes;
mod options;
mod parry_convert;
mod plan;
mod robot;
pub mod robot_init;
mod rrt;
mod search;
mod shortcut;
mod space;
mod squeeze;
mod task;
mod timing;
mod urdf_load;

pub use config::{
    CollisionConfig, GripperConfig, IkConfig, IkSolverKind, MountConfig, RobotConfig,
};
pub use enclosure::{stand_off, StandOff};
pub use error::{
    ConfigError, GripperError, IkError, JointsError, MeshFailure, PandaIkError, PlanError,
    RobotError, UrdfError,
};
pub use fk::{Drive, Kinematics, Link, Motion};
pub use geometry::{Geometry, LinkShape, RoundHull, ShapeRole};
pub use goal::{keyframe_stream, GoalOptions, GoalStrategy};
pub use hand::{Finger, HandModel, LocalBox, PUSH_SHARE};
pub use line::{distance_to_segment, LineOptions};
pub use meshes::{LinkMesh, MeshRole, PackagePath};
pub use options::{PlanBudget, PlanOptions, MS_PER_KEYFRAME};
pub use parry_convert::cylinder_axis;
pub use plan::{GripperAction, GripperEvent, LinePoses, Plan, Segment, SegmentKind};
pub use robot::{Robot, STORED_TABLES_FILE};
pub use rrt::{DynamicDomain, RrtOptions, HALVE_STEP_AFTER, MIN_STEP};
pub use search::{plan_best, plan_task, BestPlan, CandidateOutcome};
pub use squeeze::{squared_in_hand, squaring_turn};
pub use timing::{Timing, Trapezoid};
pub use urdf_load::{chain as urdf_chain, parse as parse_urdf};

/// What the criterion benchmarks in `planner/benches/` and the binary's `akl robot check`
/// tests reach below the API: each benchmark measures one of these against a baseline of its
/// own (the bidirectional RRT against a goal-biased one, the racing IK solver against k's, the
/// collision checker against every pair through parry), and the robot-check test keeps its
/// probes away from other links' meshes. Benchmarks and integration tests are crates of their
/// own that reach only public items, and the robot-check test drives the binary, so it cannot
/// move into this crate: these internals are re-exported here, hidden from the
/// documentation, and are not part of the API.
#[doc(hidden)]
pub mod internals {
    pub use crate::enclosure::point_triangle_distance;
    pub use crate::fk::{ArmJoints, UrdfJoints};
    pub use crate::ik::TracIk;
    pub use crate::parry_convert::{intersects, object_shape, robot_shape};
    pub use crate::rrt::{rrt_connect, RrtResult};
    pub use crate::space::{distance, Space};
}
