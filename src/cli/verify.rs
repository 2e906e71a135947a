//! Arguments of the commands that plan, execute and judge specs, and of the study.

use super::shared::{
    parse_pose_noise, AnyTaskArg, GateArgs, PoseNoiseArg, RobotArg, SpeedArg, TrialArgs,
};
use std::path::PathBuf;

/// `akl plan SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub(crate) struct PlanArgs {
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
pub(crate) struct FlexibilityArgs {
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

/// `akl validate SPEC --task T ...`
#[derive(Debug, clap::Args)]
pub(crate) struct ValidateArgs {
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
    /// Write the trials the gate read as JUnit XML to this file (one test case per trial named
    /// by its seed, a failed trial's root cause and detail as its failure; the gate's decision
    /// as a property), for CI test reports.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Judge the trials of this report (`akl execute --randomize N --goals sampled`, or
    /// `akl report merge` of its shards) instead of running any: the deployment gate reads them
    /// in seed order, as it reads its own, so the decision is the one `akl validate --seed`
    /// (the report's seed) gives. The spec, task, robot and settings must be the report's
    /// (checked by their hashes). Removals and answers are not judged (they need trials of
    /// other specs).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["demo", "trace", "report"])]
    pub from_report: Option<PathBuf>,
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
pub(crate) struct RelaxArgs {
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
    /// Most collision-checking work planning a widened spec's trial may take, as a multiple of
    /// the spec's own (its mean collision probes per trial over its gate); a widening whose
    /// screening trials take more on average is rejected: most poses of its regions are ones
    /// the planner must try and reject.
    #[arg(long, value_name = "X", default_value_t = 2.0)]
    pub max_effort: f64,
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
pub(crate) struct CompareArgs {
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
pub(crate) struct ExecuteArgs {
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
    /// Run only shard I of N (from 0) of the --randomize trials: a contiguous block, each
    /// trial with exactly the seed, layout and outcome it has in a single run, so `akl report
    /// merge` joins the shards' reports into the single run's. `auto` takes I and N from a
    /// Slurm job array (SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT); `auto/N` from a
    /// Kubernetes Indexed Job (JOB_COMPLETION_INDEX) of N completions.
    #[arg(
        long,
        value_name = "I/N|auto|auto/N",
        requires = "randomize",
        conflicts_with = "grounding_check"
    )]
    pub shard: Option<akl_exec::ShardRequest>,
    /// Finish the interrupted run whose report is FILE: its trials are kept, the rest of the
    /// run (or of its shard) are run, and the whole report is written to --report (default:
    /// FILE). The other options must be the run's own (checked against the report's hashes).
    #[arg(long, value_name = "FILE", requires = "randomize", conflicts_with_all = ["grounding_check", "trace"])]
    pub resume: Option<PathBuf>,
    /// Write the trials as JUnit XML to this file (one test case per trial named by its seed;
    /// a failed trial's root cause and detail as its failure), for CI test reports.
    #[arg(long, value_name = "FILE", conflicts_with = "grounding_check")]
    pub junit: Option<PathBuf>,
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

/// Where `akl execute` aims within the keyframes' TSRs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Goals {
    /// At each TSR's nominal pose when reachable.
    Nominal,
    /// Drawn at random across each TSR, as validation plans.
    Sampled,
}

/// `akl demo`
#[derive(Debug, clap::Args)]
pub(crate) struct DemoArgs {
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

/// `akl eval`
#[derive(Debug, clap::Args)]
pub(crate) struct EvalArgs {
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
    /// Run only shard I of N (from 0) of the participants: a contiguous block, each participant
    /// exactly as in the whole study; `auto` and `auto/N` as in `akl execute --shard`. Join the
    /// shards' trials.json with --merge.
    #[arg(long, value_name = "I/N|auto|auto/N")]
    pub shard: Option<akl_exec::ShardRequest>,
    /// Instead of running a study, join the trials.json files of its shards (`--shard I/N
    /// --out DIR`) into the whole study: its tables, and with --out its records and figures.
    #[arg(long, value_name = "TRIALS_JSON", num_args = 1.., conflicts_with_all = ["participants", "seed", "execute", "shard"])]
    pub merge: Vec<PathBuf>,
    /// Print the tables and every trial's scores as JSON.
    #[arg(long)]
    pub json: bool,
}
