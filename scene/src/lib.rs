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

pub mod builtin;
pub mod error;
pub mod file;
pub mod goal;
pub mod intent;
pub mod layout;
pub mod motion;
pub mod overlap;
pub mod paths;
pub mod randomize;
pub mod range;
pub mod reach;
pub mod shape;
pub mod task;
pub mod world;

pub use error::{SceneError, ShapeError};
pub use file::truth_path_for;
pub use goal::{Goal, GoalCheck};
pub use intent::{TeachStep, Teaching};
pub use layout::{check_layout, Infeasible};
pub use motion::{FixedRelation, Motion, Mover};
pub use paths::{ObjectPaths, PathSample};
pub use randomize::{randomize, randomize_layout, randomize_layout_with, Layout};
pub use range::{Groups, Range, Ranges};
pub use reach::Reach;
pub use shape::Shape;
pub use task::{Task, TASK_VERSION};
pub use world::{Object, World};
