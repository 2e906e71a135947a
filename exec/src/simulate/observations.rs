//! What a simulated run measured: everything the checks judge, read from the simulated bodies.

use crate::contacts::ContactLog;
use crate::grasp::GraspMeasure;
use akl_scene::{ObjectPaths, World};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;

/// The simulated TCP and the reference object when the plan reaches a keyframe.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyframeReach {
    /// Keyframe index in the spec.
    pub keyframe: usize,
    /// Simulated time (seconds).
    pub t: f64,
    /// The simulated TCP.
    pub tcp: Pose,
    /// The reference object's simulated pose (identity for `world`), if it exists.
    pub reference: Option<Pose>,
}

/// The simulated TCP path over one `move_in_line` segment of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePath {
    /// The keyframe the line ends at.
    pub keyframe: usize,
    /// Start and end (simulated seconds).
    pub start: f64,
    /// End.
    pub end: f64,
    /// Simulated time and TCP position, one per step, from the start to the end.
    pub points: Vec<(f64, Vector3<f64>)>,
}

/// What happened when the gripper closed at a keyframe.
#[derive(Debug, Clone, PartialEq)]
pub struct GraspEvent {
    /// The closing keyframe.
    pub keyframe: usize,
    /// When the pads stopped, or the closing ended (simulated seconds).
    pub t: f64,
    /// The object the spec closes on (the keyframe's reference).
    pub intended: String,
    /// What each pad touched when the fingers stopped.
    pub pads: [Option<String>; 2],
    /// How the object was held, when both pads touched the same object.
    pub measure: Option<GraspMeasure>,
    /// Why the grasp is not sound, when the pads closed on the intended object.
    pub unsound: Option<String>,
    /// Whether the object was welded to the hand (a sound grasp of the intended object).
    pub welded: bool,
    /// The turn (radians) by which the squeeze seated the welded object flat on the pads.
    pub squared: f64,
    /// When the load exceeded what friction holds and the object came loose.
    pub broke_at: Option<f64>,
    /// What broke it, in words (the load and what friction held), when it broke.
    pub broke_by: Option<String>,
    /// Largest displacement of the object in the hand until it was released (metres).
    pub slip: f64,
    /// When that displacement first exceeded the slip limit, if it did.
    pub slipped_at: Option<f64>,
    /// Largest force along the pads' faces the grasp carried (N).
    pub peak_load: f64,
}

/// An object let go of, and where it ended up.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseEvent {
    /// The opening keyframe.
    pub keyframe: usize,
    /// The object let go of.
    pub object: String,
    /// When (simulated seconds).
    pub t: f64,
    /// Height of the object's bottom when let go (metres).
    pub bottom_at_release: f64,
    /// Height of its bottom once it came to rest (at the end, or when grasped again).
    pub bottom_at_rest: Option<f64>,
}

/// Everything one run measured.
#[derive(Debug, Clone, Default)]
pub struct Observations {
    /// Keyframes as the plan reached them.
    pub reaches: Vec<KeyframeReach>,
    /// The simulated TCP over each line.
    pub lines: Vec<LinePath>,
    /// Every closing of the gripper.
    pub grasps: Vec<GraspEvent>,
    /// Every opening of the gripper that let go of an object.
    pub releases: Vec<ReleaseEvent>,
    /// Objects still in the hand when the plan ended.
    pub still_held: Vec<String>,
    /// Contact verdicts and extremes.
    pub contacts: ContactLog,
    /// Largest distance of the simulated TCP from the planned one (metres).
    pub tracking_max: f64,
    /// Root mean square of that distance over the plan (metres).
    pub tracking_rms: f64,
    /// Every movable object's path, sampled at [`crate::options::ExecOptions::path_rate`].
    pub paths: ObjectPaths,
    /// The world after settling.
    pub settled: Option<World>,
    /// Linear and angular speed of every movable object after settling.
    pub speeds: Vec<(String, f64, f64)>,
    /// Simulated seconds.
    pub simulated: f64,
}
