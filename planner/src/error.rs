//! Typed errors of the planner crate: loading a robot, inverse kinematics and planning.

use std::path::PathBuf;

/// Why a robot folder could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// A file of the robot folder could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// `robot.toml` is malformed or holds an invalid value.
    #[error("{}: {message}", path.display())]
    Config {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The URDF is malformed or describes something the planner cannot use.
    #[error("{}: {message}", path.display())]
    Urdf {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Mesh files the URDF names cannot be found or read: every one of them, not only the
    /// first.
    #[error("{}: {} mesh(es) cannot be read:{}", urdf.display(), failures.len(), MeshFailure::list(failures))]
    Meshes {
        /// The URDF.
        urdf: PathBuf,
        /// Each mesh that failed.
        failures: Vec<MeshFailure>,
    },
}

/// One mesh of a URDF that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshFailure {
    /// The link whose element names it.
    pub link: String,
    /// The URDF's `filename`.
    pub uri: String,
    /// Why (the package is unknown, the file is missing or unreadable).
    pub problem: String,
}

impl MeshFailure {
    /// The failures, one indented line each.
    fn list(failures: &[MeshFailure]) -> String {
        failures
            .iter()
            .map(|f| format!("\n  link `{}`: {}: {}", f.link, f.uri, f.problem))
            .collect()
    }
}

/// Why inverse kinematics found no configuration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    /// No configuration within the joint limits puts the TCP at the target.
    #[error("unreachable: no configuration within the joint limits reaches the pose")]
    Unreachable,
    /// The seed has the wrong number of joints or a non-finite value.
    #[error("bad seed: {0}")]
    BadSeed(String),
}

/// Why a spec could not be planned; every variant but [`PlanError::Options`] names the
/// keyframe or segment at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// The planning options are out of range (e.g. a speed scale of 0).
    #[error("{0}")]
    Options(String),
    /// The spec cannot be grounded in the world (unknown reference object).
    #[error("{0}")]
    Grounding(String),
    /// No whole-spec candidate was planned (a budget of none).
    #[error("no candidate was planned")]
    NoCandidate,
    /// A keyframe asks for something the world does not allow (e.g. grasping furniture).
    #[error("keyframe {keyframe}: {reason}")]
    Invalid {
        /// Index of the keyframe.
        keyframe: usize,
        /// What is wrong.
        reason: String,
    },
    /// No sampled pose of the keyframe's TSR has an inverse kinematics solution.
    #[error("keyframe {keyframe}: unreachable: none of {tried} poses sampled from its TSR has an IK solution within the joint limits")]
    Unreachable {
        /// Index of the keyframe.
        keyframe: usize,
        /// How many poses were tried.
        tried: usize,
    },
    /// Poses of the TSR are reachable, but every solution collides (or its approach does).
    #[error("keyframe {keyframe}: no collision-free IK solution among {solutions} found for {tried} sampled poses{}", blocker_text(.blocker))]
    NoCollisionFreeIk {
        /// Index of the keyframe.
        keyframe: usize,
        /// How many poses were tried.
        tried: usize,
        /// How many IK solutions were found (all rejected).
        solutions: usize,
        /// What was hit most often, if known.
        blocker: Option<String>,
    },
    /// The free-space planner ran out of its iteration budget.
    #[error("segment {segment}: planning budget exhausted ({iterations} RRT-Connect iterations without a connection)")]
    BudgetExhausted {
        /// The keyframe the segment leads to or leaves.
        keyframe: usize,
        /// The segment, e.g. `free to keyframe 2`.
        segment: String,
        /// Iterations spent.
        iterations: usize,
    },
    /// A straight-line segment cannot be followed.
    #[error("segment {segment}: {reason}")]
    Line {
        /// The keyframe the segment leads to or leaves.
        keyframe: usize,
        /// The segment, e.g. `line to keyframe 3`.
        segment: String,
        /// Why: the line leaves the workspace, a joint would jump, or it collides.
        reason: String,
    },
    /// The start configuration is in collision or outside the joint limits.
    #[error("start configuration: {0}")]
    Start(String),
}

impl PlanError {
    /// The keyframe at fault, when the error is about one (or about a segment to or from it).
    pub fn keyframe(&self) -> Option<usize> {
        match self {
            PlanError::Invalid { keyframe, .. }
            | PlanError::Unreachable { keyframe, .. }
            | PlanError::NoCollisionFreeIk { keyframe, .. }
            | PlanError::BudgetExhausted { keyframe, .. }
            | PlanError::Line { keyframe, .. } => Some(*keyframe),
            PlanError::Grounding(_)
            | PlanError::NoCandidate
            | PlanError::Start(_)
            | PlanError::Options(_) => None,
        }
    }
}

fn blocker_text(blocker: &Option<String>) -> String {
    match blocker {
        Some(b) => format!(" (most often in collision: {b})"),
        None => String::new(),
    }
}
