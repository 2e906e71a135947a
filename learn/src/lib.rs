//! Learning a task spec from one demonstration (thesis chapter 3).
//!
//! Learning knows no robot: it reads end-effector and object poses, gripper states and the
//! teacher's answers, and writes an agent-independent [`akl_tsr::TaskSpec`].
//!
//! The demonstration types, the readers and writers of its formats (JSONL, MCAP, ROS 2 bags),
//! live recording and [`learn_spec`] are at the crate root. Six modules are namespaces of
//! their own: [`calibration`] (the detector's calibration and fitting it), [`dialogue`] (the
//! question and where answers come from), [`teacher`] (the simulated teacher), [`teach`]
//! (streaming a demonstration through detector and dialogue), [`okl`] (AKL's learner and its
//! steps) and [`baselines`] (KD and mACL).

pub mod baselines;
pub mod calibration;
mod demo;
mod demo_error;
mod detector;
pub mod dialogue;
mod jsonl;
mod line_error;
mod live;
mod mcap_io;
mod mcap_read;
mod measures;
mod method;
pub mod okl;
mod recording;
mod ros2;
mod session;
mod shapes;
pub mod teach;
pub mod teacher;
mod tvd;
mod validate;

pub use calibration::Calibration;
pub use demo::{Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION};
pub use demo_error::DemoError;
pub use detector::Detector;
pub use jsonl::{read_jsonl, write_jsonl};
pub use live::{LiveEnd, LiveError, LiveStart, LiveStream};
pub use mcap_io::{read_mcap, Truncation};
pub use measures::{score, Scores, Tolerance};
pub use method::{
    learn_spec, needs_replay, prepare, recorded_answers, without_dialogue, LearnOptions, Method,
};
pub use recording::{read_demo_file, DemoFileError, DemoFormat, LoadedDemo, Recording};
pub use ros2::{import_ros2, PoseSource, Ros2Topics};
pub use session::{SessionError, TeachingSession};
pub use shapes::{prepare_shapes, read_shapes_file, ShapesError, ShapesFileError};
