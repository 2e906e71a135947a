//! What a trial is run with: the execution settings ([`ExecOptions`]) and the robot, task and
//! spec ([`Setup`]).

use crate::arm::Drives;
use crate::contacts::ContactLimits;
use crate::grasp::GraspLimits;
use crate::interrupt::Interrupt;
use crate::perception::PoseNoise;
use crate::world::Physics;
use akl_planner::{PlanOptions, Robot};
use akl_scene::Task;
use akl_tsr::TaskSpec;

/// Settings of execution.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecOptions {
    /// Simulation settings.
    pub physics: Physics,
    /// Planner settings (the seed is replaced by each trial's).
    pub plan: PlanOptions,
    /// The simulated joint servos and gripper.
    pub drives: Drives,
    /// What counts as a sound grasp.
    pub grasp: GraspLimits,
    /// How deep and hard contacts may be.
    pub contacts: ContactLimits,
    /// Perception error of the movable objects' poses.
    pub noise: PoseNoise,
    /// How far the TCP may leave a `move_in_line` segment's line (metres).
    pub line_tolerance: f64,
    /// How far a held object may move in the hand (metres).
    pub slip_limit: f64,
    /// How far a released object may fall (metres).
    pub drop_limit: f64,
    /// Simulated seconds of settling after the plan, before the goals are checked.
    pub settle: f64,
    /// Longest settling (simulated seconds after the plan): past `settle`, the simulation goes
    /// on while an object still moves faster than `rest_speed`, up to this. A part that rocks
    /// for a moment in a clamp is then judged at rest, as a person would wait for it, while an
    /// object that never comes to rest still fails the rest check.
    pub settle_max: f64,
    /// Speed below which an object counts as at rest (m/s; ten times that in rad/s).
    pub rest_speed: f64,
    /// Samples per simulated second of the objects' paths.
    pub path_rate: f64,
    /// Raised to stop part-way (Ctrl-C): once it is, batches start no more trials (see
    /// [`Interrupt`]). Never raised by default. Not a setting of the trials themselves:
    /// it changes which trials run, never what one of them gives.
    pub interrupt: Interrupt,
}

impl Default for ExecOptions {
    fn default() -> Self {
        ExecOptions {
            physics: Physics::default(),
            plan: PlanOptions::default(),
            drives: Drives::default(),
            grasp: GraspLimits::default(),
            contacts: ContactLimits::default(),
            noise: PoseNoise::default(),
            line_tolerance: 0.005,
            slip_limit: 0.005,
            drop_limit: 0.02,
            settle: 0.5,
            settle_max: 2.0,
            rest_speed: 0.01,
            path_rate: 240.0,
            interrupt: Interrupt::NEVER,
        }
    }
}

/// What a trial needs besides its world: the robot, the task and the spec.
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a> {
    /// The robot.
    pub robot: &'a Robot,
    /// The task (its nominal world, goals and ranges).
    pub task: &'a Task,
    /// The spec executed.
    pub spec: &'a TaskSpec,
    /// Settings.
    pub options: &'a ExecOptions,
}
