//! Command-line arguments.

mod bench;
mod inspect;
mod report;
mod shared;
mod teaching;
mod verify;

pub(crate) use bench::*;
pub(crate) use inspect::*;
pub(crate) use report::*;
pub(crate) use shared::*;
pub(crate) use teaching::*;
pub(crate) use verify::*;

use clap::{Parser, Subcommand};

/// Teach a robot arm a multistep task from one demonstration, as the least restrictive
/// sequence of Task Space Region keyframes, and check the learned spec before it runs.
#[derive(Debug, Parser)]
#[command(name = "akl", version, about, long_about = None)]
pub(crate) struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The top-level commands.
#[derive(Debug, Subcommand)]
pub(crate) enum Command {
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
    /// true (no trace); a second signal exits at once; --resume REPORT runs only the trials it
    /// lacks.
    ///
    /// On a cluster: --shard I/N runs block I (from 0) of N of the trials, with the seeds they
    /// have in a single run (--shard auto reads a Slurm job array's or, as auto/N, a Kubernetes
    /// Indexed Job's index), and `akl report merge` joins the shards' reports into the report
    /// of the whole run (README, "Clusters and CI"); --junit FILE writes one test case per
    /// trial for CI systems.
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
    /// the widening), or once its planning takes more than --max-effort times the spec's own
    /// collision probes. Everything screening kept is then gated at once on fresh seeds (from
    /// SEED + 1,000,000; at most 299 trials unless --max-trials, so it passes only with no
    /// failure); each failed trial is replayed with one keyframe's widening undone at a time,
    /// only the keyframes whose undoing passes it are halved (twice at most, then dropped), and
    /// the rest is gated again. Every probe and gate is printed as it ends. The gain is given as
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
    /// Measure the planner on shared problem sets, side by side with other planners.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Work with report files: merge the reports of a run's shards.
    #[command(subcommand)]
    Report(ReportCommand),
}
