//! Arguments of the commands that calibrate, teach, learn and score.

use std::path::PathBuf;

/// `akl calibrate`
#[derive(Debug, clap::Args)]
#[command(
    after_help = "The line is labelled constrained and the circle unconstrained; the \
logistic model of the switching probability (β0, β1) is fitted to them by maximum likelihood, \
and the energy tank's dissipation T_d and threshold T_s follow from the fitted model on the same \
data. Without a calibration, `akl teach` uses the one fitted to the simulated default teacher."
)]
pub(crate) struct CalibrateArgs {
    /// Demonstration of a straight line (JSONL or MCAP).
    #[arg(
        long,
        required_unless_present = "simulate",
        conflicts_with = "simulate"
    )]
    pub line: Option<PathBuf>,
    /// Demonstration of a circle (JSONL or MCAP).
    #[arg(
        long,
        required_unless_present = "simulate",
        conflicts_with = "simulate"
    )]
    pub circle: Option<PathBuf>,
    /// Calibrate a simulated teacher instead (see --profile and --seed).
    #[arg(long)]
    pub simulate: bool,
    /// Simulated teacher profile: default, careful, novice or straight.
    #[arg(long, default_value = "default", requires = "simulate")]
    pub profile: String,
    /// Seed of the simulated teacher's movements.
    #[arg(long, default_value_t = 0, requires = "simulate")]
    pub seed: u64,
    /// Where to write the calibration (JSON).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Who demonstrates in `akl teach`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Teacher {
    /// The simulated teacher, following the task's teaching steps.
    Sim,
    /// A robot driver streaming JSONL frames on standard input.
    Stdin,
}

/// `akl teach`
#[derive(Debug, clap::Args)]
#[command(
    after_help = "ANSWERS is `oracle` (a simulated teacher who knows the task's true \
lines and errs at its profile's rate; --teacher sim only), `all-yes`, `terminal` (asked on \
/dev/tty: one key, y, n or ?), or a list: `yes,no,unknown` used in order, or keyed by the time \
of the question each answers, `9.9:yes,19.0:no` (the question within 0.5 s of the time). A list \
must hold one answer per question: a question without an answer, or an answer left over, stops \
with exit 2 and lists the questions with their times and hand positions. Defaults: oracle with \
--teacher sim, terminal with --teacher stdin.

The recording streams into OUTPUT.partial and is renamed to OUTPUT when complete; a killed \
recording leaves OUTPUT.partial, which `akl learn` reads up to its last second. Ctrl-C ends a \
recording cleanly. The spec learned with AKL is written next to it as <OUTPUT stem>.spec.json."
)]
pub(crate) struct TeachArgs {
    /// Task: a built-in name or a task file (required with --teacher sim).
    #[arg(long)]
    pub task: Option<String>,
    /// Who demonstrates.
    #[arg(long, value_enum, default_value = "sim")]
    pub teacher: Teacher,
    /// Simulated teacher profile: default, careful, novice or straight.
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Seed of the simulated teacher.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Who answers the learner's questions (see below).
    #[arg(long)]
    pub answers: Option<String>,
    /// Calibration file from `akl calibrate` (default: the shipped one).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Play the simulated teacher in real time instead of as fast as possible.
    #[arg(long)]
    pub realtime: bool,
    /// Recording rate of the simulated teacher in Hz (default: its profile's, 100; at most 1000).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Where to record the demonstration: a .mcap or .jsonl file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl learn`
#[derive(Debug, clap::Args)]
#[command(
    after_help = "AKL learns from the detector's states and the answers a recording holds. \
With --answers the detector is replayed over the recording and its questions answered anew \
(all-yes, terminal, or a list such as yes,no or 9.9:yes,19.0:no, one answer per question). A \
recording without the detector's states (e.g. a JSONL file from another driver) is replayed \
with its own recorded answers, keyed by their questions' times, or needs --answers when it has \
none."
)]
pub(crate) struct LearnArgs {
    /// The demonstration (JSONL or MCAP, also a .partial file of a killed recording).
    pub demo: PathBuf,
    /// Learning method: akl, kd or macl.
    #[arg(long, default_value = "akl")]
    pub method: String,
    /// Task whose world grounds the keyframes (default: the demo's task, when built in).
    #[arg(long)]
    pub task: Option<String>,
    /// Calibration the detector ran with (default: the shipped one).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Answers for replaying the detector over the demo, instead of the recording's own.
    #[arg(long)]
    pub answers: Option<String>,
    /// Half-widths of every learned TSR: metres on x, y, z and radians on roll, pitch, yaw.
    #[arg(long, value_name = "METRES,RADIANS", default_value = "0.005,0.05")]
    pub bounds: String,
    /// Read DEMO as a ROS 2 bag: the end effector's geometry_msgs/msg/PoseStamped topic, or
    /// `tf:FRAME` for a frame of the transform tree.
    #[arg(long, value_name = "TOPIC|tf:FRAME", help_heading = "ROS 2 bags")]
    pub ros_ee: Option<String>,
    /// An object of the bag, by the name the task gives it (repeat for every object).
    #[arg(
        long = "ros-object",
        value_name = "NAME=TOPIC|tf:FRAME",
        requires = "ros_ee",
        help_heading = "ROS 2 bags"
    )]
    pub ros_objects: Vec<String>,
    /// The sensor_msgs/msg/JointState topic holding the finger joints.
    #[arg(
        long,
        value_name = "TOPIC",
        default_value = "/joint_states",
        help_heading = "ROS 2 bags"
    )]
    pub ros_gripper: String,
    /// The frame the demonstration is expressed in (the robot base of the task's world).
    #[arg(long, default_value = "world", help_heading = "ROS 2 bags")]
    pub ros_frame: String,
    /// The gripper counts as closed while its finger joints sum to less than this (metres).
    #[arg(long, default_value_t = 0.075, help_heading = "ROS 2 bags")]
    pub ros_closed_below: f64,
    /// A JSON file of the bag's object shapes by name, written as in a task file (mesh files
    /// relative to it): a release is then grounded on what it rests on by the task world's
    /// support rule.
    #[arg(
        long,
        value_name = "FILE",
        requires = "ros_ee",
        help_heading = "ROS 2 bags"
    )]
    pub ros_shapes: Option<PathBuf>,
    /// Where to write the spec (JSON).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the spec and timing as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl score`
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Keyframes are paired in order (longest common subsequence): a keyframe \
matches when kind, reference, gripper and constraint agree, a pose when its target is within \
2 cm and 0.2 rad after grounding both specs on the truth's object poses. Accuracies are \
intersection over union; constraint accuracy compares line lengths. Success means the learned \
spec equals the truth. Exit code 0 whatever the score."
)]
pub(crate) struct ScoreArgs {
    /// The learned spec.
    pub spec: PathBuf,
    /// The ground truth: a spec file, or a built-in task name for its ground truth.
    #[arg(long)]
    pub truth: String,
    /// Print the measures as JSON.
    #[arg(long)]
    pub json: bool,
}
