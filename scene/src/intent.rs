//! The teaching intent: what a simulated teacher does, step by step, to demonstrate a task.
//!
//! The intent is not a spec: it says where the teacher's hand goes, and the learner has to
//! discover the keyframes from the recorded motion. Poses are tool-centre-point (TCP) poses with
//! the gripper's z axis pointing out of the fingers.

use crate::error::SceneError;
use akl_tsr::pose::serde_pose;
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};

/// One step of a demonstration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case", deny_unknown_fields)]
pub enum TeachStep {
    /// Reach `object` (approaching along the tool axis) and close the gripper with the TCP at
    /// `tcp`, given in the object's frame. The object then moves with the hand.
    Grasp {
        /// The object to grasp.
        object: String,
        /// TCP pose in the object's frame at the moment the gripper closes.
        #[serde(with = "serde_pose")]
        tcp: Pose,
    },
    /// Put the held object down on `on` at `place` (the object's pose in the support's frame)
    /// and open the gripper.
    Release {
        /// The support the held object is put on.
        on: String,
        /// Held object's pose in the support's frame once released.
        #[serde(with = "serde_pose")]
        place: Pose,
    },
    /// Move freely (a curved, hand-like path) to the TCP pose `to`, given in `relative_to`'s frame.
    Move {
        /// Target TCP pose.
        #[serde(with = "serde_pose")]
        to: Pose,
        /// Object whose frame `to` is in, or `world`.
        relative_to: String,
    },
    /// Move in a straight line, because the task requires it, to the TCP pose `to` in
    /// `relative_to`'s frame.
    Line {
        /// Target TCP pose.
        #[serde(with = "serde_pose")]
        to: Pose,
        /// Object whose frame `to` is in, or `world`.
        relative_to: String,
    },
}

/// How the simulated teacher demonstrates a task: a start pose and the steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Teaching {
    /// TCP pose (world frame) where the demonstration starts and the gripper is open.
    #[serde(with = "serde_pose")]
    pub start: Pose,
    /// The steps, in order.
    pub steps: Vec<TeachStep>,
}

impl TeachStep {
    /// The objects this step mentions.
    pub fn objects(&self) -> Vec<&str> {
        match self {
            TeachStep::Grasp { object, .. } => vec![object],
            TeachStep::Release { on, .. } => vec![on],
            TeachStep::Move { relative_to, .. } | TeachStep::Line { relative_to, .. } => {
                vec![relative_to]
            }
        }
    }

    /// The step in words, e.g. `grasp part` or `line (relative to shelf_2)`.
    pub fn describe(&self) -> String {
        match self {
            TeachStep::Grasp { object, .. } => format!("grasp {object}"),
            TeachStep::Release { on, .. } => format!("release on {on}"),
            TeachStep::Move { relative_to, .. } => format!("move freely (target in {relative_to})"),
            TeachStep::Line { relative_to, .. } => {
                format!("move in a straight line (target in {relative_to})")
            }
        }
    }
}

impl Teaching {
    /// The world TCP pose at the end of each step, with the objects where `world` has them.
    ///
    /// A release's pose follows from the support, the place and the grasp that picked the held
    /// object up; the error names a step that refers to an object the world lacks.
    pub fn targets(&self, world: &crate::World) -> Result<Vec<Pose>, SceneError> {
        let frame = |name: &str| -> Result<Pose, String> {
            if name == akl_tsr::WORLD_FRAME {
                return Ok(Pose::identity());
            }
            world
                .object(name)
                .map(|o| o.pose)
                .ok_or_else(|| format!("unknown object `{name}`"))
        };
        let mut grasp: Option<Pose> = None;
        let mut targets = Vec::with_capacity(self.steps.len());
        for (i, step) in self.steps.iter().enumerate() {
            let at = |problem: String| SceneError::invalid(format!("teaching.steps[{i}]"), problem);
            let target = match step {
                TeachStep::Grasp { object, tcp } => {
                    grasp = Some(*tcp);
                    frame(object).map_err(at)? * tcp
                }
                TeachStep::Release { on, place } => {
                    let tcp = grasp
                        .take()
                        .ok_or_else(|| at("releases while holding nothing".into()))?;
                    frame(on).map_err(at)? * place * tcp
                }
                TeachStep::Move { to, relative_to } | TeachStep::Line { to, relative_to } => {
                    frame(relative_to).map_err(at)? * to
                }
            };
            targets.push(target);
        }
        Ok(targets)
    }
}
