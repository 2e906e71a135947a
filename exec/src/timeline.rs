//! A trial as a trace shows it: the frames of its simulation, the plan and the perceived world.

use crate::contacts::ContactPoint;
use akl_planner::{Plan, PlanError};
use akl_scene::World;
use akl_tsr::Pose;

/// One instant of a simulation, for a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Simulated time (seconds).
    pub t: f64,
    /// World pose of every robot link, in the robot's link order.
    pub links: Vec<Pose>,
    /// World pose of every object, in the task's order.
    pub objects: Vec<Pose>,
    /// The simulated arm joint positions.
    pub joints: Vec<f64>,
    /// The simulated gripper opening (metres).
    pub width: f64,
    /// Contacts of the arm and the held object since the previous frame.
    pub contacts: Vec<ContactPoint>,
}

/// A trial as a trace shows it: the worlds, the plan, and the simulation's frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Frames per simulated second.
    pub rate: f64,
    /// The frames, in time order (none when planning failed).
    pub frames: Vec<Frame>,
    /// The plan executed, when there was one.
    pub plan: Option<Plan>,
    /// The world the planner perceived.
    pub perceived: Option<World>,
    /// Why planning failed, when it did.
    pub planning_failure: Option<PlanError>,
}

impl Timeline {
    /// An empty timeline recording `rate` frames per simulated second.
    pub fn new(rate: f64) -> Timeline {
        Timeline {
            rate,
            frames: Vec::new(),
            plan: None,
            perceived: None,
            planning_failure: None,
        }
    }
}
