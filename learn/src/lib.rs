//! Learning a task spec from one demonstration (thesis chapter 3).
//!
//! Learning knows no robot: it reads end-effector and object poses, gripper states and the
//! teacher's answers, and writes an agent-independent [`akl_tsr::TaskSpec`].

pub mod demo;
pub mod measures;
pub mod okl;
pub mod tvd;

pub use demo::{Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION};
