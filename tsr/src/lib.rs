//! Core types of AKL: rigid poses, Task Space Regions (TSRs), keyframes and task specifications.
//!
//! A task specification is an ordered list of keyframes; each keyframe is a TSR (Berenson,
//! Srinivasa & Kuffner 2011) expressed relative to a reference object, plus the gripper state
//! commanded once it is reached and the constraint on the segment that ends at it. Specs are
//! agent independent: nothing here knows about a robot.
//!
//! Math types are nalgebra `f64`, of the version the kinematics crate `k` is built on, so the
//! whole workspace shares one nalgebra.

pub mod error;
pub mod io;
pub mod keyframe;
pub mod pose;
pub mod rpy;
pub mod spec;
pub mod tsr;

pub use error::{BoundsError, FileError, PoseError, SpecError};
pub use keyframe::{Constraint, Gripper, Keyframe, KeyframeKind};
pub use pose::{Pose, PoseJson};
pub use spec::{TaskSpec, SPEC_VERSION, WORLD_FRAME};
pub use tsr::{Bounds, Tsr, ROTATION_WEIGHT};

/// The nalgebra version shared with `k`, re-exported so dependants need no direct dependency.
pub use nalgebra;
