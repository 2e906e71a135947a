//! Core types of AKL: rigid poses, Task Space Regions (TSRs), keyframes and task specifications.
//!
//! A task specification is an ordered list of keyframes; each keyframe is a TSR (Berenson,
//! Srinivasa & Kuffner 2011) expressed relative to a reference object, plus the gripper state
//! commanded once it is reached and the constraint on the segment that ends at it. Specs are
//! agent independent: nothing here knows about a robot.
//!
//! Math types are nalgebra `f64`, of the version the kinematics crate `k` is built on, so the
//! whole workspace shares one nalgebra.
//!
//! The types are at the crate root; three modules are namespaces of free functions: `pose`
//! (building and comparing poses, `serde_pose`), `rpy` (roll-pitch-yaw) and `io` (atomic
//! writes, readable JSON).

mod error;
pub mod io;
mod keyframe;
pub mod pose;
pub mod rpy;
mod spec;
mod tsr;

pub use error::{describe_json_error, BoundsError, FileError, PoseError, SpecError};
pub use keyframe::{Constraint, Gripper, Keyframe, KeyframeKind};
pub use pose::{Pose, PoseJson};
pub use spec::{TaskSpec, SPEC_VERSION, WORLD_FRAME};
pub use tsr::{Bounds, Tsr, COORDINATE_NAMES, ROTATION_WEIGHT};

/// The nalgebra version shared with `k`, re-exported so dependants need no direct dependency.
pub use nalgebra;
