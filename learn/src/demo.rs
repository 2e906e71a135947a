//! A recorded demonstration, stored column-wise: one vector per stream, all indexed by frame.
//!
//! Columns keep the per-frame streams contiguous, which is what the detector and OKL scan, and
//! cost no allocation per frame however many objects the scene has.

use std::collections::BTreeMap;

use akl_scene::Shape;
use akl_tsr::{Gripper, Pose};
use serde::{Deserialize, Serialize};

/// The `akl_demo` version this build reads and writes.
pub const DEMO_VERSION: u32 = 1;

/// What a recording is of: first line of a JSONL demo, metadata record of an MCAP demo.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemoHeader {
    /// Format version; always [`DEMO_VERSION`].
    pub akl_demo: u32,
    /// Name of the task demonstrated (a built-in task or any other).
    pub task: String,
    /// Frame all poses are expressed in; `world`.
    pub frame: String,
    /// Calibration the online detector used, if any (as recorded, e.g. a file name or `default`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
    /// Shapes of tracked objects, by name, as a task file writes them (see [`read_shapes_file`](crate::read_shapes_file)):
    /// with them a release is grounded by the task world's support rule when no task world is
    /// given. Empty when the recording declares none.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub shapes: BTreeMap<String, Shape>,
}

/// The teacher's answer to "Do I have to move in a straight line there?".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Answer {
    /// The line is required by the task.
    Yes,
    /// The line is not required; the learner drops it.
    No,
    /// The teacher does not know; the learner keeps the line.
    Unknown,
}

/// What happened in the dialogue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "event", content = "value")]
pub enum DialogueKind {
    /// The learner asked whether the detected line is required.
    Query,
    /// The teacher answered the last query.
    Answer(Answer),
    /// The learner suggested not moving in lines unless required.
    Suggestion,
    /// The teacher marked the current pose as a keyframe (keyframe demonstrations, KD).
    Keyframe,
}

/// One dialogue event, with when it happened.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DialogueEvent {
    /// Demonstration time (seconds).
    pub t: f64,
    /// Index of the frame at or just before `t`.
    pub frame: usize,
    /// What happened.
    pub kind: DialogueKind,
}

/// The poses of one object over the demonstration, one per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectTrack {
    /// Object name, as in the task's world.
    pub name: String,
    /// Pose at each frame.
    pub poses: Vec<Pose>,
}

/// A demonstration: per-frame streams of equal length plus the dialogue.
#[derive(Debug, Clone, PartialEq)]
pub struct Demo {
    /// What the recording is of.
    pub header: DemoHeader,
    /// Time of each frame (seconds, strictly increasing).
    pub times: Vec<f64>,
    /// End-effector (tool centre point) pose at each frame.
    pub ee: Vec<Pose>,
    /// Gripper state at each frame.
    pub gripper: Vec<Gripper>,
    /// Every object's pose at each frame.
    pub objects: Vec<ObjectTrack>,
    /// Online detector state Y_c at each frame (true = constrained), when it ran; empty if not.
    pub detector: Vec<bool>,
    /// Queries, answers, suggestions and marked keyframes, in time order.
    pub events: Vec<DialogueEvent>,
}

impl DemoHeader {
    /// The header of a recording of `task` in the world frame, calibration not yet named.
    pub fn new(task: impl Into<String>) -> Self {
        DemoHeader {
            akl_demo: DEMO_VERSION,
            task: task.into(),
            frame: akl_tsr::WORLD_FRAME.to_string(),
            calibration: None,
            shapes: BTreeMap::new(),
        }
    }
}

impl Demo {
    /// A demonstration with no frames yet, tracking the named objects.
    pub fn empty(header: DemoHeader, objects: &[String]) -> Self {
        Demo {
            header,
            times: Vec::new(),
            ee: Vec::new(),
            gripper: Vec::new(),
            objects: objects
                .iter()
                .map(|name| ObjectTrack {
                    name: name.clone(),
                    poses: Vec::new(),
                })
                .collect(),
            detector: Vec::new(),
            events: Vec::new(),
        }
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether the demo has no frames.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}
