//! Worlds, task files, randomization and goal predicates for AKL.
//!
//! A [`World`] is the robot's base pose and a set of named objects with shapes, poses and
//! physical properties. A [`Task`] is a world plus what may move (randomization ranges and
//! rigid groups, within layouts the task can be done in), what the task is for (goal
//! predicates on the end state and the objects' paths), how a simulated teacher demonstrates
//! it (the teaching intent) and its ground-truth least restrictive spec. The three study tasks
//! of the thesis (§4.4) are built in.
//!
//! What a simulation calls: [`randomize`] for a trial's layout, [`ObjectPaths`] to record the
//! objects' paths while it runs, [`Task::check_goals`] on the settled end world, and
//! [`Task::fixed_relations`] to know which groundings no layout can tell apart.
//!
//! Everything is at the crate root but the built-in tasks, which are looked up by name in
//! [`builtin`].

pub mod builtin;
mod error;
mod file;
mod goal;
mod intent;
mod layout;
mod motion;
mod overlap;
mod paths;
mod randomize;
mod range;
mod reach;
mod shape;
mod task;
mod world;

pub use error::{SceneError, ShapeError};
pub use file::load_obstacles;
pub use goal::{Goal, GoalCheck};
pub use intent::{TeachStep, Teaching};
pub use motion::{FixedRelation, Motion, Mover};
pub use overlap::shapes_overlap;
pub use paths::{ObjectPaths, PathSample};
pub use randomize::{randomize, randomize_layout_with, Layout};
pub use range::{Groups, Range, Ranges};
pub use reach::Reach;
pub use shape::Shape;
pub use task::{Task, TASK_VERSION};
pub use world::{Object, World, SUPPORT_GAP};
