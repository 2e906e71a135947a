//! Keyframes: a TSR with a reference object, a gripper command and a path constraint.

use crate::tsr::Tsr;
use serde::{Deserialize, Serialize};
use std::fmt;

/// What a keyframe captures (thesis §3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KeyframeKind {
    /// A physical interaction: a grasp or a release.
    Interaction,
    /// A boundary of a constrained motion segment.
    Constraint,
    /// An interaction that coincides with a constraint boundary.
    Combined,
}

/// The gripper state commanded once a keyframe is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gripper {
    /// Fingers open (0 in the thesis).
    Open,
    /// Fingers closed (1 in the thesis).
    Closed,
}

/// The constraint on the motion segment that ends at a keyframe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Constraint {
    /// Any collision-free motion.
    None,
    /// The end effector moves on the straight line from the previous keyframe to this one.
    MoveInLine,
}

/// One step of a task: reach a pose in `tsr` (grounded on `reference`), then command `gripper`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Interaction, constraint or combined.
    pub kind: KeyframeKind,
    /// Object w the TSR is expressed relative to: the key object of the next interaction.
    pub reference: String,
    /// Where the end effector must be; `t0_w` is the reference object's pose when learned.
    pub tsr: Tsr,
    /// Gripper state commanded once this keyframe is reached.
    pub gripper: Gripper,
    /// Constraint on the segment that ends at this keyframe.
    pub constraint: Constraint,
    /// Demonstration time (seconds) this keyframe was learned from, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// Demonstration frame index this keyframe was learned from, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<u64>,
}

impl fmt::Display for KeyframeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            KeyframeKind::Interaction => "interaction",
            KeyframeKind::Constraint => "constraint",
            KeyframeKind::Combined => "combined",
        })
    }
}

impl fmt::Display for Gripper {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Gripper::Open => "open",
            Gripper::Closed => "closed",
        })
    }
}

impl fmt::Display for Constraint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Constraint::None => "none",
            Constraint::MoveInLine => "move_in_line",
        })
    }
}
