//! Learning a task spec from one demonstration (thesis chapter 3).
//!
//! Learning knows no robot: it reads end-effector and object poses, gripper states and the
//! teacher's answers, and writes an agent-independent [`akl_tsr::TaskSpec`].

pub mod baselines;
pub mod calibration;
pub mod demo;
pub mod demo_error;
pub mod detector;
pub mod dialogue;
pub mod jsonl;
pub mod line_error;
pub mod live;
pub mod mcap_io;
mod mcap_read;
pub mod measures;
pub mod method;
pub mod okl;
pub mod recording;
pub mod ros2;
pub mod session;
pub mod shapes;
pub mod teach;
pub mod teacher;
pub mod tvd;
pub mod validate;

pub use calibration::Calibration;
pub use demo::{Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION};
pub use demo_error::DemoError;
pub use detector::Detector;
pub use jsonl::{read_jsonl, write_jsonl};
pub use method::{learn_spec, prepare, LearnOptions, Method};
