//! Worlds, task files and randomization for AKL.
//!
//! A [`World`] is the robot's base pose and a set of named objects with shapes, poses and
//! physical properties. A [`Task`] is a world plus what may move (randomization ranges), what
//! must hold at the end (goal predicates), how a simulated teacher demonstrates it (the teaching
//! intent) and its ground-truth least restrictive spec. The three study tasks of the thesis
//! (§4.4) are built in.

pub mod builtin;
pub mod error;
pub mod goal;
pub mod intent;
pub mod overlap;
pub mod randomize;
pub mod shape;
pub mod task;
pub mod world;

pub use error::SceneError;
pub use goal::{Goal, GoalCheck};
pub use intent::{TeachStep, Teaching};
pub use randomize::{randomize, Range, Ranges};
pub use shape::Shape;
pub use task::{Task, TASK_VERSION};
pub use world::{Object, World};
