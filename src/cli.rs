//! Command-line arguments.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Teach a robot arm a multistep task from one demonstration, as the least restrictive
/// sequence of Task Space Region keyframes, and check the learned spec before it runs.
#[derive(Debug, Parser)]
#[command(name = "akl", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// List and inspect tasks (built-in or from a task file).
    #[command(subcommand)]
    Task(TaskCommand),
    /// Validate and inspect task specifications (spec.json).
    #[command(subcommand)]
    Spec(SpecCommand),
    /// Fit a teacher's online-detector calibration from a straight line and a circle.
    Calibrate(CalibrateArgs),
    /// Record a demonstration while the online detector asks about straight lines.
    Teach(TeachArgs),
    /// Learn a task spec from a recorded demonstration (AKL, or the KD and mACL baselines).
    Learn(LearnArgs),
    /// Score a learned spec against a ground truth (keyframe, pose and constraint accuracy).
    Score(ScoreArgs),
    /// Inspect the robot model: joints and limits, forward and inverse kinematics.
    #[command(subcommand)]
    Robot(RobotCommand),
    /// Plan a spec for the robot in a task's world: one timed joint trajectory.
    ///
    /// Each keyframe is grounded on the objects' poses; free segments are planned with
    /// RRT-Connect and shortcut, move_in_line segments keep the tool centre point on the
    /// straight line, grasps and releases are approached along the tool axis. Prints per
    /// segment its kind, duration and planning time.
    ///
    /// Exit codes: 0 planned; 2 bad input (a missing or invalid spec file, an unknown task, a
    /// spec naming objects the task does not have, a bad robot folder); 1 the spec cannot be
    /// planned (the message names the keyframe or segment and why: unreachable, no
    /// collision-free IK solution, planning budget exhausted, the line leaves the workspace or
    /// collides) or the output cannot be written.
    Plan(PlanArgs),
    /// Execute a spec in simulation with the objects moved around, and verify every trial.
    ///
    /// Each trial places the task's movable objects at random within the ranges of its task
    /// file (--randomize N; without it, one trial where the task file puts them), plans the
    /// spec in that world and runs the plan in a rapier3d simulation: the arm follows the timed
    /// trajectory, a closing gripper attaches the object between its fingers, an opening one
    /// lets it settle. A trial passes only when every keyframe was reached within its TSR
    /// grounded on the reference object's current pose, every move_in_line segment kept the
    /// tool centre point within 5 mm of its line, the arm and the held object touched nothing
    /// but what the step manipulates, and the task's goals hold once the objects have settled.
    /// Trial i uses seed S + i for both the placement and the planner, so a run is
    /// reproducible whatever --jobs is.
    ///
    /// A trial's failures are ordered by the simulated time they occurred; the first is its
    /// root cause. Prints the trials, how many passed, the failed trials counted by root cause
    /// (unreachable, no plan, collision, grasp failed, keyframe missed, line deviation, goal
    /// not met; these add up to the failed trials), the causes also seen in failed trials but
    /// not as their root, the worst line deviation and the time per trial, then the failed
    /// trials and their root cause. A progress bar shows on standard error when it is a
    /// terminal.
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops starting trials: the trials under way finish, the
    /// summary of the finished ones is printed and the report written with "interrupted":
    /// true (no trace); a second signal exits at once.
    ///
    /// Exit codes: 0 every trial passed; 1 some trial failed (or an output cannot be written);
    /// 2 bad input (a missing or invalid spec file, an unknown task, a spec naming objects the
    /// task does not have, a bad option value or output folder); 130 interrupted by SIGINT or
    /// SIGTERM (with --grounding-check too).
    Execute(ExecuteArgs),
    /// How much freedom a spec leaves the planner: bits of freedom, and what the planner makes
    /// of it in randomized scenes.
    ///
    /// Bits of freedom: the tool centre point's workspace is a lattice of 5 cm cells (within
    /// the robot's reach, without the cells inside furniture, objects where the task file puts
    /// them). A trace is a walk over neighbouring cells from the TCP at the ready pose back to
    /// it, of at most 1.25 times the steps of the task's teaching route, that meets every
    /// keyframe's region (the cells its TSR reaches) in order and keeps every move_in_line
    /// segment on the cells of its line. Traces are counted exactly; the measure is log2 of
    /// the count. Each keyframe's share is the bits the spec gains without it (and without the
    /// lines at it); each line's, without that line. Adding a keyframe or a line never adds
    /// bits, so redundant keyframes and unintended lines show as shares that cost bits.
    ///
    /// The planner's gains: the spec is planned in --scenes randomized scenes of the task with
    /// the budget (--budget, as in `akl plan`); printed are the success rate and the best and
    /// median execution time and joint-path length, beside the nominal-first candidate.
    ///
    /// Exit codes: 0 measured; 2 bad input (a missing or invalid spec file, an unknown task, a
    /// spec naming objects the task does not have); 1 a randomized scene cannot be made.
    Flexibility(FlexibilityArgs),
    /// Gate a deployment: the spec must succeed with probability at least P (at confidence C)
    /// and be least restrictive.
    ///
    /// The spec's randomized trials (as `akl execute --randomize`, but with every keyframe's
    /// goal drawn at random within its TSR, so the whole region is tried, not its centre) are
    /// judged one by one in seed order by a sequential test, run in batches on every core until
    /// it decides: it passes once the exact one-sided upper confidence bound (Clopper-Pearson,
    /// at --confidence) of the failure rate is at most 1 - P (--min-success), fails once the
    /// lower bound exceeds it, and is undecided after --max-trials. With the defaults (P 0.99,
    /// C 0.95, 2,000 trials) a spec that never fails passes at trial 299, a spec failing 0.1 %
    /// of trials passes 99.45 % of the time, one failing 2 % fails 98.9 % of the time, one
    /// failing every trial fails at trial 1; the verdict never depends on --jobs.
    ///
    /// A spec that passes is then judged without each keyframe and each move_in_line by the
    /// same gate on the same seeds: a removal that passes it is not essential (the spec is not
    /// the least restrictive one, thesis Theorem 3.2.3), one that fails it is essential, else
    /// undecided. With --demo (the recording the spec was learned from) each of the teacher's
    /// answers is flipped, the demonstration learned again with AKL and the result gated: a
    /// "no" is contradicted when the spec fails and restoring the line passes; a "yes" (or "I
    /// don't know") when dropping the line passes. Every failed trial of the spec is listed with
    /// the `akl execute` command that replays it (--goals sampled draws the same goals).
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops starting trials: what was judged is printed and the
    /// report written with "interrupted": true; a second signal exits at once.
    ///
    /// Exit codes: 0 passes (and minimal); 1 fails (or an output cannot be written); 2 bad
    /// input (a missing or invalid spec or demo, an unknown task, a spec naming objects the task
    /// does not have, a bad option); 3 undecided; 4 not minimal (passes, but a removal passes
    /// too or an answer is contradicted); 130 interrupted by SIGINT or SIGTERM.
    Validate(ValidateArgs),
    /// Widen every keyframe's TSR as far as the deployment gate allows, and write the result.
    ///
    /// The spec itself must first pass the gate (as `akl validate`). Then, keyframe by keyframe,
    /// each of x, y, z, roll, pitch and yaw is widened symmetrically to the widest of its whole
    /// limit (10 cm, pi/2 for roll and pitch, pi for yaw), a quarter or a sixteenth of it that
    /// passes a screening: up to --screen trials, dropped at the first trial it fails that the
    /// spec before it passes on the same seed (the spec's own rare failures are not blamed on
    /// the widening). What a keyframe kept is then gated on fresh seeds (from SEED + 1,000,000);
    /// if the gate does not pass it, the keyframe's widening is halved and gated again, twice
    /// at most, then dropped. Every probe and gate is printed as it ends. The gain is given as
    /// TSR log-volume (one bit per doubled width, rotation included) beside the bits of
    /// execution traces (see `akl flexibility`).
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops: the widest spec that passed a gate so far is written,
    /// marked interrupted; a second signal exits at once.
    ///
    /// Exit codes: 0 a relaxed spec passed its gate and was written (atomically); 1 the spec
    /// fails its own gate or no widening passed one (nothing is written); 2 bad input; 130
    /// interrupted by SIGINT or SIGTERM (the best gated spec, if any, written).
    Relax(RelaxArgs),
    /// Compare specs of one task: keyframes, lines, bits of freedom, planning, execution and
    /// the validation verdict, one row per spec.
    ///
    /// Bits of freedom as `akl flexibility`; plan success and best duration from the budgeted
    /// planner over --scenes randomized scenes (as `akl flexibility`); the pass rate and the
    /// verdict from `akl validate`'s gate (--min-success, --confidence, --max-trials); the pass
    /// rate is given with its exact 95 % interval.
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops starting trials: the specs compared so far are printed
    /// (the one under way with the trials it finished and no verdict) and marked interrupted; a
    /// second signal exits at once.
    ///
    /// Exit codes: 0 compared (whatever the verdicts); 2 bad input (a missing or invalid spec,
    /// named); 130 interrupted by SIGINT or SIGTERM; 1 anything else.
    Compare(CompareArgs),
    /// The whole loop on a built-in task: teach, learn, then execute with randomized objects.
    ///
    /// The simulated teacher demonstrates the task while the online detector asks about its
    /// straight lines (answered by an oracle that knows the task), AKL learns the spec from
    /// the recording, and the spec is executed in simulation with the objects moved around.
    /// Prints each stage's result and writes into the output folder: demo.mcap (the
    /// demonstration), spec.json (the learned spec), report.json (every trial's checks) and
    /// trace.mcap (one trial, the first that failed or else the first, for Foxglove).
    ///
    /// Exit codes: 0 every trial passed; 1 some trial failed; 2 bad input.
    Demo(DemoArgs),
    /// The thesis's user study, simulated: AKL against KD and mACL on the built-in tasks.
    ///
    /// A fixed population of simulated participants (teacher profiles drawn from ranges set
    /// from the thesis's reported behaviour: speed, tremor, curvature, straight free motion,
    /// wrong and "I don't know" answers, keyframe-marking habits, how they take suggestions)
    /// calibrates, then teaches each built-in task with each method in a Latin-square order of
    /// methods (thesis §4.4). What a participant takes from AKL's suggestions carries into its
    /// later demonstrations. Every learned spec is scored against the task's ground truth
    /// (keyframe, pose and constraint accuracy, success; thesis §4.2).
    ///
    /// Prints the success rate per task and method (cf. Table 4.1, case (a)), AKL's constraint
    /// errors and what the answers did (cf. Table 4.2), and the learning runtime per method
    /// (cf. §4.6.8); with --execute, the mean pass rate of the specs in simulation. --out
    /// writes trials.csv (a row per trial), trials.json (the population, participants,
    /// calibrations, every trial with its spec, and the tables) and four SVG figures:
    /// keyframes.svg, poses.svg, constraint_length.svg (missed + incorrect per trial, cf.
    /// Figures 4-2b, 4-4b, 4-6a) and runtime.svg (log scale, cf. Figure 4-9). A progress bar
    /// shows on standard error when it is a terminal. The same seed gives the same study
    /// (runtimes aside).
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops starting trials: the trials under way finish (with
    /// their executions), and the tables and --out records cover the finished trials, marked
    /// interrupted; a second signal exits at once.
    ///
    /// Exit codes: 0 the study ran; 2 bad input (no participants, --execute 0, an output
    /// folder that is a file); 130 interrupted by SIGINT or SIGTERM; 1 anything else.
    Eval(EvalArgs),
}

/// `akl eval`
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Number of simulated participants (the thesis had 12).
    #[arg(long, default_value_t = 12)]
    pub participants: usize,
    /// Seed of the draw of participants and of everything they do.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Execute every learned spec N times in simulation with the objects moved around, and
    /// report the pass rates (each run plans and simulates the whole task).
    #[arg(long, value_name = "N")]
    pub execute: Option<usize>,
    /// Folder for trials.csv, trials.json and the SVG figures (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the tables and every trial's scores as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `--speed-scale S`, shared by the commands that plan.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct SpeedArg {
    /// How fast the arm may move, in (0, 1]: joint velocity limits times S, accelerations
    /// times S² (MoveIt's scaling factors S and S²), fingers at S times their speed, the pause
    /// after the gripper 1/S as long: the whole plan takes 1/S as long. 1 (the default) moves
    /// as fast as the robot allows. Recorded in reports.
    #[arg(long, value_name = "S", default_value_t = 1.0, value_parser = parse_speed_scale)]
    pub speed_scale: f64,
}

fn parse_speed_scale(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1.0 => Ok(s),
        _ => Err(format!("expected a number in (0, 1], got `{text}`")),
    }
}

/// `--any-task`, shared by the commands that run a spec in a task.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct AnyTaskArg {
    /// Run the spec even though its `task` field names another task than --task (refused by
    /// default: a spec given another task's world is almost always a mistake).
    #[arg(long)]
    pub any_task: bool,
}

/// `--robot DIR`, shared by the commands that use a robot.
#[derive(Debug, Clone, clap::Args)]
pub struct RobotArg {
    /// Robot folder (robot.toml and its URDF); the built-in Franka Panda if omitted.
    #[arg(long, value_name = "DIR")]
    pub robot: Option<PathBuf>,
}

/// `akl robot ...`
#[derive(Debug, Subcommand)]
pub enum RobotCommand {
    /// Show the robot: joints, limits, ready pose, gripper, links and collision margins.
    Info {
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Forward kinematics: the TCP and flange poses (robot base frame) of a configuration.
    ///
    /// Exits with 2 if the joint list is malformed, has the wrong length or leaves the limits.
    Fk {
        /// Joint positions in radians, comma-separated, base to tip (e.g. 0,-0.785,0,-2.356,0,1.571,0.785).
        #[arg(long, value_name = "Q1,...,Qn", allow_hyphen_values = true)]
        joints: String,
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Inverse kinematics: the configuration nearest a seed that puts the TCP at a pose.
    ///
    /// The pose is in the robot base frame. Exits with 1 and says "unreachable" if no
    /// configuration within the joint limits reaches it; with 2 if the input is malformed.
    Ik {
        /// Target TCP pose: position (m) and unit quaternion, comma-separated.
        #[arg(long, value_name = "X,Y,Z,QX,QY,QZ,QW", allow_hyphen_values = true)]
        pose: String,
        /// Seed configuration (default: the ready pose).
        #[arg(long, value_name = "Q1,...,Qn", allow_hyphen_values = true)]
        seed_joints: Option<String>,
        #[command(flatten)]
        robot: RobotArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

/// `akl plan SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The spec file to plan.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec is planned in.
    #[arg(long)]
    pub task: String,
    /// Seed of the planner's random choices (same seed, same plan).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Planning budget in milliseconds: the planner plans whole-spec candidates, spreading
    /// goals across every TSR and IK branch, and keeps the quickest. The budget is converted
    /// to a fixed number of candidates (1 + MS / (3.8 ms x keyframes), calibrated on the
    /// reference machine, see BENCHMARKS.md), so the plan depends on the seed and budget only,
    /// never on the machine's speed or load. 0 plans one candidate, every keyframe on its
    /// nominal pose when reachable.
    #[arg(long, value_name = "MS", default_value_t = 200)]
    pub budget: u64,
    /// Write the full plan (timed trajectory and gripper events) as JSON to this file.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the per-segment summary as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// `akl flexibility SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub struct FlexibilityArgs {
    /// The spec file to measure.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec is measured in.
    #[arg(long)]
    pub task: String,
    /// Randomized scenes to plan the spec in (0: bits of freedom only).
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub scenes: usize,
    /// Planning budget per scene in milliseconds (as `akl plan --budget`).
    #[arg(long, value_name = "MS", default_value_t = 200)]
    pub budget: u64,
    /// Scene i is placed and planned with seed SEED + i.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the report as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// Trial settings shared by `akl validate`, `relax` and `compare`.
#[derive(Debug, Clone, clap::Args)]
pub struct TrialArgs {
    /// Trials run in parallel (default: the number of cores).
    #[arg(long, value_name = "J")]
    pub jobs: Option<usize>,
    /// Perception error of the movable objects' poses (as `akl execute --pose-noise`).
    #[arg(long, value_name = "MM,DEG", default_value = "2,1", value_parser = parse_pose_noise)]
    pub pose_noise: PoseNoiseArg,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// What the deployment gate asks (shared by `akl validate`, `relax` and `compare`).
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct GateArgs {
    /// The success probability the spec must be shown to reach.
    #[arg(long, value_name = "P", default_value_t = 0.99)]
    pub min_success: f64,
    /// The confidence each look of the sequential test shows it at.
    #[arg(long, value_name = "C", default_value_t = 0.95)]
    pub confidence: f64,
    /// Trials after which the gate stops undecided (default 2,000; for `akl relax`, whose
    /// undecided widenings are dropped, 1,000).
    #[arg(long, value_name = "N", alias = "randomize")]
    pub max_trials: Option<usize>,
}

/// `akl validate SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub struct ValidateArgs {
    /// The spec file to validate.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec runs in.
    #[arg(long)]
    pub task: String,
    #[command(flatten)]
    pub gate: GateArgs,
    /// Seed of the first trial (trial i uses SEED + i).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the spec's trials (those the gate read, every check) as JSON to this file, in
    /// the format of `akl execute --report`.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Write trial N of the spec's trials (default: the first that failed, else the first) as
    /// an MCAP trace, as `akl execute --trace`.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Which of the spec's trials --trace writes.
    #[arg(long, value_name = "N", requires = "trace")]
    pub trace_trial: Option<usize>,
    /// The demonstration the spec was learned from (JSONL or MCAP): check the teacher's answers.
    #[arg(long, value_name = "DEMO")]
    pub demo: Option<PathBuf>,
    /// Calibration the demonstration's detector ran with (default: the shipped one).
    #[arg(long, value_name = "FILE", requires = "demo")]
    pub calibration: Option<PathBuf>,
    #[command(flatten)]
    pub trials: TrialArgs,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the validation as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl relax SPEC --task T -o relaxed.json`
#[derive(Debug, clap::Args)]
pub struct RelaxArgs {
    /// The spec file to relax.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec runs in.
    #[arg(long)]
    pub task: String,
    /// Where to write the relaxed spec.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: PathBuf,
    /// Most screening trials of one widening.
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub screen: usize,
    #[command(flatten)]
    pub gate: GateArgs,
    /// Seed of the search's first trial; the gates use seeds from SEED + 1,000,000.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub run: TrialArgs,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the relaxation as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl compare SPEC... --task T`
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// The spec files to compare.
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Task (built-in name or task file) whose world the specs run in.
    #[arg(long)]
    pub task: String,
    #[command(flatten)]
    pub gate: GateArgs,
    /// Randomized scenes the budgeted planner plans each spec in.
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub scenes: usize,
    /// Planning budget per scene in milliseconds (as `akl plan --budget`).
    #[arg(long, value_name = "MS", default_value_t = 200)]
    pub budget: u64,
    /// Seed of the first trial and scene.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub trials: TrialArgs,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the rows as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl execute SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub struct ExecuteArgs {
    /// The spec file to execute.
    pub spec: PathBuf,
    /// Task (built-in name or task file) whose world the spec runs in.
    #[arg(long)]
    pub task: String,
    /// Run N trials with the movable objects placed at random within the task's ranges
    /// (without it: one trial with the objects where the task file puts them).
    #[arg(long, value_name = "N")]
    pub randomize: Option<usize>,
    /// Seed of the first trial's placement and planning (trial i uses SEED + i).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Trials run in parallel (default: the number of cores).
    #[arg(long, value_name = "J")]
    pub jobs: Option<usize>,
    /// Write one trial (the first that failed, else the first) as an MCAP trace for Foxglove:
    /// link transforms over time, objects, keyframe TSRs, lines and events.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Planning budget per trial in milliseconds (as `akl plan --budget`); 0 plans one
    /// candidate, the nominal-first plan.
    #[arg(long, value_name = "MS", default_value_t = 0)]
    pub budget: u64,
    /// Where the planner aims within each keyframe's TSR: `nominal` (its centre when
    /// reachable) or `sampled` (drawn at random across the region, up to 8 whole-spec draws,
    /// as `akl validate` plans: replays a validation trial; overrides --budget).
    #[arg(long, value_enum, default_value_t = Goals::Nominal)]
    pub goals: Goals,
    /// Instead of executing the spec, re-ground each keyframe on every other object (and the
    /// world), its offset recomputed so its nominal pose is unchanged, and judge each such
    /// spec by the deployment gate of `akl validate` (goals drawn across the TSRs; its default
    /// P 0.99 and C 0.95, --randomize N its most trials, default 2,000): prints, per keyframe,
    /// which references the task's randomization tells apart from the spec's (the gate fails
    /// the re-grounded spec: validation would reject it), which it cannot (the gate passes
    /// it), which are undecided, and which are equivalent (held in a fixed relation by the
    /// task or by an earlier placement), each with its failed trials and their 95 % interval.
    #[arg(long, conflicts_with_all = ["trace", "report"])]
    pub grounding_check: bool,
    /// Which trial `--trace` writes (default: the first that failed, else the first).
    #[arg(long, value_name = "N", requires = "trace")]
    pub trace_trial: Option<usize>,
    /// Write the full report (every trial's checks) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Perception error of the movable objects' poses that the planner sees: standard
    /// deviations in millimetres (along world x and y) and degrees (about the vertical);
    /// `0,0` plans on the true poses.
    #[arg(long, value_name = "MM,DEG", default_value = "2,1", value_parser = parse_pose_noise)]
    pub pose_noise: PoseNoiseArg,
    #[command(flatten)]
    pub fit: AnyTaskArg,
    #[command(flatten)]
    pub robot: RobotArg,
    /// Print the full report as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// `--pose-noise MM,DEG`: standard deviations of perceived position (mm) and yaw (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseNoiseArg {
    /// Millimetres.
    pub millimetres: f64,
    /// Degrees.
    pub degrees: f64,
}

fn parse_pose_noise(text: &str) -> Result<PoseNoiseArg, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [mm, deg] = parts[..] else {
        return Err(format!("expected MM,DEG (e.g. 2,1), got `{text}`"));
    };
    let number = |s: &str, what: &str| -> Result<f64, String> {
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
            _ => Err(format!("{what} must be a number >= 0, got `{s}`")),
        }
    };
    Ok(PoseNoiseArg {
        millimetres: number(mm, "millimetres")?,
        degrees: number(deg, "degrees")?,
    })
}

/// `akl demo`
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Built-in task (see `akl task list`) or task file to teach.
    #[arg(long, default_value = "inspection")]
    pub task: String,
    /// Folder the demonstration, spec, report and trace are written to (created if missing).
    #[arg(long, value_name = "DIR", default_value = "akl-out")]
    pub out: PathBuf,
    /// Seed of the simulated teacher and of the first trial.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of randomized trials the learned spec is executed in.
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub trials: usize,
    /// Trials run in parallel (default: the number of cores).
    #[arg(long, value_name = "J")]
    pub jobs: Option<usize>,
    #[command(flatten)]
    pub speed: SpeedArg,
}

/// `akl calibrate`
#[derive(Debug, clap::Args)]
#[command(
    after_help = "The line is labelled constrained and the circle unconstrained; the \
logistic model of the switching probability (β0, β1) is fitted to them by maximum likelihood, \
and the energy tank's dissipation T_d and threshold T_s follow from the fitted model on the same \
data. Without a calibration, `akl teach` uses the one fitted to the simulated default teacher."
)]
pub struct CalibrateArgs {
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

/// Where `akl execute` aims within the keyframes' TSRs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Goals {
    /// At each TSR's nominal pose when reachable.
    Nominal,
    /// Drawn at random across each TSR, as validation plans.
    Sampled,
}

/// Who demonstrates in `akl teach`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Teacher {
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
/dev/tty: one key, y, n or ?), or a list such as `yes,no,unknown` used in order. Defaults: \
oracle with --teacher sim, terminal with --teacher stdin.

The recording streams into OUTPUT.partial and is renamed to OUTPUT when complete; a killed \
recording leaves OUTPUT.partial, which `akl learn` reads up to its last second. Ctrl-C ends a \
recording cleanly. The spec learned with AKL is written next to it as <OUTPUT stem>.spec.json."
)]
pub struct TeachArgs {
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
    after_help = "A demonstration recorded without the online detector (e.g. a JSONL file \
from another driver) is first replayed through it for AKL; its questions are answered by \
--answers (all-yes, terminal or a list such as yes,no)."
)]
pub struct LearnArgs {
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
    /// Answers for replaying the detector over a demo recorded without it.
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
pub struct ScoreArgs {
    /// The learned spec.
    pub spec: PathBuf,
    /// The ground truth: a spec file, or a built-in task name for its ground truth.
    #[arg(long)]
    pub truth: String,
    /// Print the measures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `akl task ...`
#[derive(Debug, Subcommand)]
pub enum TaskCommand {
    /// List the built-in tasks.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show a task: its objects, every randomization range and rigid group, the layout rules,
    /// the fixed relations (groundings no randomized trial can tell apart), its goals, its
    /// teaching steps and its ground truth.
    Show {
        /// A built-in task name (see `akl task list`) or the path of a task file.
        task: String,
        /// Print the task file as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// `akl spec ...`
#[derive(Debug, Subcommand)]
pub enum SpecCommand {
    /// Validate a spec and summarize it: keyframes, kinds, references and constraints.
    ///
    /// References are checked against the objects of the task named in the spec when it is a
    /// built-in task, or of the task given with --task. Exits with 2 if the spec is invalid.
    Check {
        /// The spec file.
        file: PathBuf,
        /// Task (built-in name or task file) whose objects the references must name.
        #[arg(long)]
        task: Option<String>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a spec's keyframes as a table (or JSON).
    Show {
        /// The spec file.
        file: PathBuf,
        /// Print the spec as JSON.
        #[arg(long)]
        json: bool,
    },
}
