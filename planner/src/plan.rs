//! The result of planning a spec: one timed joint trajectory made of segments, with the
//! gripper events at the keyframes. Serializable to JSON (`akl plan -o plan.json`).

use crate::contact_rules::Allowances;
use crate::timing::Timing;
use akl_tsr::pose::serde_pose;
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `akl_plan` version this build reads and writes.
pub(crate) const PLAN_VERSION: u32 = 1;

/// What a segment does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentKind {
    /// Collision-free motion in joint space (RRT-Connect, shortcut).
    Free,
    /// The TCP on a straight line, because the spec requires it (`move_in_line`).
    Line,
    /// Straight TCP move along the tool axis onto a grasp or placement.
    Approach,
    /// Straight TCP move back along the tool axis after a grasp, lifting the object.
    Lift,
    /// Straight TCP move back along the tool axis after a release.
    Retreat,
    /// The arm stands still while the gripper opens or closes.
    Gripper,
}

impl SegmentKind {
    /// Lower-case name, as in JSON.
    pub fn name(&self) -> &'static str {
        match self {
            SegmentKind::Free => "free",
            SegmentKind::Line => "line",
            SegmentKind::Approach => "approach",
            SegmentKind::Lift => "lift",
            SegmentKind::Retreat => "retreat",
            SegmentKind::Gripper => "gripper",
        }
    }
}

/// The grounded straight line a TCP follows (world frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinePoses {
    /// TCP pose at the start.
    #[serde(with = "serde_pose")]
    pub from: Pose,
    /// TCP pose at the end.
    #[serde(with = "serde_pose")]
    pub to: Pose,
}

/// One piece of the trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// What it does.
    pub kind: SegmentKind,
    /// The keyframe it leads to (or, for lift, retreat and gripper, the one it follows).
    pub keyframe: usize,
    /// Start time (seconds from the start of the plan).
    pub start: f64,
    /// End time.
    pub end: f64,
    /// Wall-clock seconds spent planning it.
    pub planning_time: f64,
    /// Gripper opening during the segment (metres); for a gripper segment, the opening at its
    /// end (it changes linearly from the previous one).
    pub width: f64,
    /// The object held during the segment, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holding: Option<String>,
    /// Contacts allowed during the segment (everything else counts as a collision).
    #[serde(default, skip_serializing_if = "Allowances::is_empty")]
    pub allowed: Allowances,
    /// For straight-line segments, the grounded start and end TCP poses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<LinePoses>,
    /// Joint waypoints (arm joints).
    pub waypoints: Vec<Vec<f64>>,
    /// How the waypoints are timed.
    pub timing: Timing,
}

/// Opening or closing the gripper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GripperAction {
    /// Close on an object (grasp).
    Close,
    /// Open (release).
    Open,
}

/// A gripper command at a keyframe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GripperEvent {
    /// When the command starts (seconds); the arm holds still for the gripper's travel time.
    pub t: f64,
    /// Open or close.
    pub action: GripperAction,
    /// The keyframe it belongs to.
    pub keyframe: usize,
    /// The object grasped or released.
    pub object: String,
    /// On a grasp, the object it is lifted from (if any); on a release, the support it is
    /// placed on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// Finger opening once the command completes (metres).
    pub width: f64,
    /// On a grasp, the object's pose in the TCP frame; on a release, its planned world pose.
    #[serde(with = "serde_pose")]
    pub object_pose: Pose,
}

/// A planned task: the timed trajectory of the arm joints and the gripper events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Format version; always 1 (`PLAN_VERSION`).
    pub akl_plan: u32,
    /// The task planned.
    pub task: String,
    /// The robot's name.
    pub robot: String,
    /// Arm joint names, the order of every configuration.
    pub joint_names: Vec<String>,
    /// The seed the plan was made with.
    pub seed: u64,
    /// Total duration (seconds).
    pub duration: f64,
    /// The segments, back to back in time.
    pub segments: Vec<Segment>,
    /// Gripper commands in time order.
    pub events: Vec<GripperEvent>,
}

/// Why a plan file cannot be read.
#[cfg(test)]
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub(crate) enum PlanFileError {
    /// The text is not JSON of the plan format (serde's message names line and column).
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    /// The `akl_plan` version is not the one this build reads.
    #[error("unsupported plan version {0} (this build reads akl_plan {PLAN_VERSION})")]
    Version(u32),
}

impl Plan {
    /// The segment running at time `t` (clamped to the plan).
    pub(crate) fn segment_at(&self, t: f64) -> Option<&Segment> {
        let i = self.segments.partition_point(|s| s.end < t);
        self.segments.get(i).or_else(|| self.segments.last())
    }

    /// The arm joint positions at time `t` (clamped to `[0, duration]`).
    pub fn sample(&self, t: f64) -> Vec<f64> {
        let t = t.clamp(0.0, self.duration);
        match self.segment_at(t) {
            Some(s) => s.timing.sample(&s.waypoints, t - s.start),
            None => Vec::new(),
        }
    }

    /// The gripper opening at time `t`: constant within motion segments, changing linearly
    /// during gripper segments.
    pub fn gripper_width(&self, t: f64) -> f64 {
        let t = t.clamp(0.0, self.duration);
        let i = self.segments.partition_point(|s| s.end < t);
        let Some(s) = self.segments.get(i).or_else(|| self.segments.last()) else {
            return 0.0;
        };
        if s.kind != SegmentKind::Gripper || s.end <= s.start {
            return s.width;
        }
        let before = if i > 0 {
            self.segments[i - 1].width
        } else {
            s.width
        };
        let f = ((t - s.start) / (s.end - s.start)).clamp(0.0, 1.0);
        before + f * (s.width - before)
    }

    /// Total joint-space length of the arm's motion (radians, Euclidean over the joints),
    /// summed over the segments' waypoints.
    pub(crate) fn joint_path_length(&self) -> f64 {
        self.segments
            .iter()
            .map(|s| crate::space::path_length(&s.waypoints))
            .sum()
    }

    /// The plan as pretty JSON.
    pub(crate) fn to_json(&self) -> serde_json::Result<String> {
        akl_tsr::io::to_readable_json(self)
    }

    /// Parses a plan; the error names the line and column (the tests' round trip: nothing
    /// else reads plan files).
    #[cfg(test)]
    pub(crate) fn from_json(text: &str) -> Result<Plan, PlanFileError> {
        let plan: Plan = serde_json::from_str(text)?;
        if plan.akl_plan != PLAN_VERSION {
            return Err(PlanFileError::Version(plan.akl_plan));
        }
        Ok(plan)
    }

    /// Writes the plan atomically (never a half-written file).
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let text = self.to_json().map_err(std::io::Error::other)?;
        akl_tsr::io::write_atomic(path, text.as_bytes())
    }
}
