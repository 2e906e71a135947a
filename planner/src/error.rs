//! Typed errors of the planner crate: loading a robot, inverse kinematics and planning.

use std::path::PathBuf;

/// Why a robot folder could not be loaded.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The simulation cannot drive the robot's gripper.
    #[error("{}: [gripper]: {source}", path.display())]
    Gripper {
        /// The `robot.toml` whose gripper it is.
        path: PathBuf,
        /// Why.
        source: GripperError,
    },
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
    /// The robot's stored self-collision tables are malformed.
    #[error("{}: {source}", path.display())]
    StoredTables {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: crate::collision::StoredTablesError,
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

/// Why the simulation cannot drive a robot's gripper; the robot is refused when loaded.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GripperError {
    /// The opening moves other than two finger joints.
    #[error("the gripper moves {} joint(s) ({}): the simulation drives exactly two prismatic fingers (list them in [gripper] joints, or one of them when the other mimics it)", .0.len(), .0.join(", "))]
    FingerCount(Vec<String>),
    /// A finger joint turns: a linkage gripper.
    #[error("gripper joint `{0}` is not prismatic: the simulation drives two prismatic fingers, or a linkage (a revolute knuckle listed in [gripper] joints, whose mimic joints move two fingertips)")]
    NotPrismatic(String),
    /// A linkage's knuckle moves other than two fingertips (leaf links).
    #[error("the linkage moves {} fingertip link(s) ({}): the simulation drives a linkage whose knuckle moves exactly two", .0.len(), .0.join(", "))]
    LinkageTips(Vec<String>),
    /// A revolute gripper turns its fingertip instead of keeping it parallel.
    #[error("fingertip `{0}` turns as the gripper closes: the simulation drives prismatic fingers or a parallel linkage (fingertips kept parallel, as the Robotiq 2F-85's)")]
    NotParallel(String),
    /// The two fingers are not both mounted on one link by parallel slides.
    #[error("the two finger joints must slide along one axis on one hand link")]
    TwoHands,
    /// A finger link has no primitive collision element to make its pad from.
    #[error("finger link `{0}` has no primitive collision element (box, cylinder, sphere) to grasp with: the simulation makes the finger's pad from the element reaching furthest towards the other finger")]
    NoPad(String),
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

/// Why a URDF cannot be used; names the joint or link at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UrdfError {
    /// The file is a xacro template, which must be expanded into a URDF first.
    #[error("this is a xacro file, not a URDF: expand it first (`xacro robot.urdf.xacro > robot.urdf`, from ROS's xacro package) and name the .urdf in robot.toml")]
    Xacro,
    /// The XML is malformed or not a URDF (urdf-rs's message).
    #[error("{0}")]
    Xml(String),
    /// Two links, or two joints, have one name.
    #[error("two {0} share a name")]
    DuplicateName(&'static str),
    /// A joint is of an unsupported type, names an unknown link or has bad numbers.
    #[error("joint `{joint}`: {problem}")]
    Joint {
        /// The joint.
        joint: String,
        /// What is wrong with it.
        problem: String,
    },
    /// The links do not hang from exactly one root.
    #[error("links must form one tree with one root; roots found: {}", .0.join(", "))]
    NotOneTree(Vec<String>),
    /// The joints close a loop.
    #[error("the joints form a cycle through link `{0}`")]
    Cycle(String),
    /// `robot.toml` names a link or joint the URDF lacks.
    #[error("{field} `{name}` is not a {kind} of the URDF")]
    NotInUrdf {
        /// The `robot.toml` field, e.g. `tcp_link`.
        field: &'static str,
        /// The name given.
        name: String,
        /// `link` or `joint`.
        kind: &'static str,
    },
    /// No joint between the base and the TCP moves.
    #[error("no movable joint between the base and `{0}`")]
    NoArmJoint(String),
    /// Several of the problems above, every one found in the file.
    #[error("{} problems:{}", .0.len(), .0.iter().map(|p| format!("\n  {p}")).collect::<String>())]
    Several(Vec<UrdfError>),
    /// A collision element has a size of zero or less.
    #[error("link `{link}`: collision geometry {geometry} has a non-positive size")]
    Geometry {
        /// The link.
        link: String,
        /// The geometry as read.
        geometry: String,
    },
}

/// Why `robot.toml` holds a value the robot cannot have.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The TOML is malformed or lacks a field (the parser's message, with line and column).
    #[error("{0}")]
    Toml(String),
    /// A limit, width, speed or margin is not a positive number.
    #[error("{field} must be positive and finite, got {value}")]
    NotPositive {
        /// The field, e.g. `velocity_limits[2]`.
        field: String,
        /// Its value.
        value: f64,
    },
    /// The ready configuration holds NaN or an infinity.
    #[error("ready holds a non-finite number ({0})")]
    ReadyNotFinite(f64),
    /// The mount pose holds NaN or an infinity.
    #[error("mount holds a non-finite number ({0})")]
    MountNotFinite(f64),
}

/// Why a joint configuration is not one the arm can take; names the joint.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum JointsError {
    /// The configuration has the wrong number of values.
    #[error("expected {} joint values ({}), got {got}", names.len(), names.join(", "))]
    Count {
        /// The arm's joints.
        names: Vec<String>,
        /// How many values were given.
        got: usize,
    },
    /// A value is NaN or infinite.
    #[error("joint {} (`{name}`) is not finite", index + 1)]
    NotFinite {
        /// Index of the joint (0-based).
        index: usize,
        /// Its name.
        name: String,
    },
    /// A value lies outside the joint's limits.
    #[error("joint {} (`{name}`) = {value} is outside its limits [{lo}, {hi}]", index + 1)]
    OutsideLimits {
        /// Index of the joint (0-based).
        index: usize,
        /// Its name.
        name: String,
        /// The value.
        value: f64,
        /// Lower limit.
        lo: f64,
        /// Upper limit.
        hi: f64,
    },
}

/// Why the analytic Panda solver does not fit an arm's kinematics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PandaIkError {
    /// The arm does not have seven joints.
    #[error("the panda solver needs 7 arm joints, this arm has {0}")]
    JointCount(usize),
    /// Fewer than seven joints lie between the base and the TCP.
    #[error("the TCP is not seven joints away from the base")]
    ShortChain,
    /// An arm joint differs from the Panda's.
    #[error("joint `{joint}` (joint {}): {problem}", index + 1)]
    Joint {
        /// The joint's name.
        joint: String,
        /// Its index in the arm (0-based).
        index: usize,
        /// How it differs.
        problem: String,
    },
    /// A length the Panda has as zero is not.
    #[error("the panda solver needs {name} = 0, found {value}")]
    NonZero {
        /// The Denavit–Hartenberg parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A joint between joint 7 and the TCP moves.
    #[error("joint `{0}` between joint 7 and the TCP is not fixed")]
    MovingTip(String),
}

/// Why inverse kinematics found no configuration.
#[non_exhaustive]
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
#[non_exhaustive]
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
