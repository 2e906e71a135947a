//! `akl execute SPEC --task T`, and the execution stage of `akl demo`.

use super::robot::load as load_robot;
use super::{check_output, print_json};
use crate::cli::{ExecuteArgs, Goals, PoseNoiseArg};
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::batch::{Batch, BatchOptions};
use akl_exec::error::ExecError;
use akl_exec::perception::PoseNoise;
use akl_exec::report::{BatchReport, Cause};
use akl_exec::ExecOptions;
use akl_planner::PlanBudget;
use akl_planner::{PlanOptions, Robot};
use akl_scene::Task;
use akl_stats::GateOptions;
use akl_tsr::{FileError, TaskSpec};
use akl_validate::grounding::GroundingOptions;
use akl_validate::trials::verifying;
use serde::Serialize;
use std::path::Path;

/// How many failed trials the table lists one by one.
const LISTED_FAILURES: usize = 10;

/// One execution: a spec on a task, the trials, and where the outputs go.
pub(crate) struct Execution<'a> {
    /// The robot.
    pub robot: &'a Robot,
    /// The task.
    pub task: &'a Task,
    /// The spec.
    pub spec: &'a TaskSpec,
    /// The spec's file, to name it in messages.
    pub spec_path: &'a Path,
    /// Randomized trials, or `None` for one trial with the task's own placements.
    pub randomize: Option<usize>,
    /// Seed of the first trial.
    pub seed: u64,
    /// Trials in parallel (`None`: the number of cores).
    pub jobs: Option<usize>,
    /// Where to write the trace.
    pub trace: Option<&'a Path>,
    /// Which trial the trace shows (`None`: the first that failed, else the first).
    pub trace_trial: Option<usize>,
    /// Settings of execution.
    pub options: ExecOptions,
    /// Where to write the report.
    pub report: Option<&'a Path>,
}

/// The outcome of an execution, as `--json` prints it.
#[derive(Serialize)]
pub(crate) struct Executed {
    /// The spec file.
    pub spec: String,
    /// The report file written, if any.
    pub report_file: Option<String>,
    /// The trace file written, if any.
    pub trace_file: Option<String>,
    /// The trial the trace shows.
    pub trace_trial: Option<usize>,
    /// The report.
    #[serde(flatten)]
    pub report: BatchReport,
}

pub(super) fn run(args: ExecuteArgs) -> CliResult {
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let spec = super::load_spec_for(&args.spec, &task, args.fit)?;
    let options = ExecOptions {
        plan: PlanOptions {
            budget: PlanBudget::from_millis(args.budget, spec.keyframes.len()),
            speed_scale: args.speed.speed_scale,
            ..PlanOptions::default()
        },
        noise: pose_noise(args.pose_noise),
        interrupt: crate::stop::interrupt(),
        ..ExecOptions::default()
    };
    let options = match args.goals {
        Goals::Nominal => options,
        Goals::Sampled => verifying(&options),
    };
    if args.grounding_check {
        let defaults = GroundingOptions::default();
        let grounding = GroundingOptions {
            gate: GateOptions {
                max_trials: match args.randomize {
                    Some(0) => {
                        return Err(CliError::input("--randomize: needs at least one trial"))
                    }
                    Some(n) => n,
                    None => defaults.gate.max_trials,
                },
                ..defaults.gate
            },
            seed: args.seed,
            jobs: jobs(args.jobs)?,
        };
        return super::grounding::run(
            &robot, &task, &spec, &args.spec, &options, &grounding, args.json,
        );
    }
    let executed = execute(&Execution {
        robot: &robot,
        task: &task,
        spec: &spec,
        spec_path: &args.spec,
        randomize: args.randomize,
        seed: args.seed,
        jobs: args.jobs,
        trace: args.trace.as_deref(),
        trace_trial: args.trace_trial,
        options,
        report: args.report.as_deref(),
    })?;
    if args.json {
        print_json(&executed)?;
    } else {
        print_executed(&executed);
        print_outputs(&executed);
    }
    if executed.report.interrupted {
        return Err(CliError::interrupted(format!(
            "interrupted: {} of {} trials finished",
            executed.report.trials,
            args.randomize.unwrap_or(1)
        )));
    }
    verdict(&executed.report)
}

/// The perception error `--pose-noise` asks for.
pub(crate) fn pose_noise(arg: PoseNoiseArg) -> PoseNoise {
    PoseNoise {
        position: arg.millimetres * 1e-3,
        yaw: arg.degrees.to_radians(),
    }
}

/// The worker threads `--jobs` asks for (default: the number of cores).
pub(crate) fn jobs(asked: Option<usize>) -> Result<usize, CliError> {
    match asked {
        Some(0) => Err(CliError::input("--jobs: needs at least one")),
        Some(j) => Ok(j),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// Exit code 1 when some trial failed.
pub(crate) fn verdict(report: &BatchReport) -> CliResult {
    if report.all_passed() {
        Ok(())
    } else {
        Err(CliError::internal(format!(
            "{} of {} trials failed",
            report.trials - report.passed,
            report.trials
        )))
    }
}

/// Runs the trials of `e`, showing progress, and writes the report and trace. Once
/// `e.options.interrupt` is raised no more trials start: the report of those that finished
/// is written (marked interrupted) and the trace is not.
pub(crate) fn execute(e: &Execution) -> Result<Executed, CliError> {
    if let Some(p) = e.trace {
        check_output(p, "trace")?;
    }
    if let Some(p) = e.report {
        check_output(p, "report")?;
    }
    let trials = match e.randomize {
        Some(0) => return Err(CliError::input("--randomize: needs at least one trial")),
        Some(n) => n,
        None => 1,
    };
    let jobs = jobs(e.jobs)?;
    let options = BatchOptions {
        trials,
        randomize: e.randomize.is_some(),
        seed: e.seed,
        jobs: jobs.min(trials),
    };
    if let Some(i) = e.trace_trial.filter(|&i| i >= trials) {
        return Err(CliError::input(format!(
            "--trace-trial {i}: there are only {trials} trials (0 to {})",
            trials - 1
        )));
    }
    let batch =
        Batch::new(e.robot, e.task, e.spec, &e.options, options).map_err(|err| match err {
            ExecError::Spec(source) => CliError::input(FileError {
                path: e.spec_path.to_path_buf(),
                source,
            }),
            ExecError::Scene(source) => {
                CliError::input(format!("task `{}`: {source}", e.task.name))
            }
            other => CliError::input(other),
        })?;
    let progress = Progress::new(&format!("executing on `{}`", e.task.name), trials);
    let report = batch
        .run(&|r| progress.tick(r.passed))
        .map_err(CliError::internal);
    progress.finish();
    let report = report?;
    let written = |p: Option<&Path>| p.map(|p| p.display().to_string());
    if let Some(p) = e.report {
        report
            .save(p)
            .map_err(|err| CliError::internal(format!("{}: {err}", p.display())))?;
    }
    let trace_trial = match e.trace.filter(|_| !report.interrupted) {
        Some(p) => Some(
            batch
                .write_trace(&report, e.trace_trial, p)
                .map_err(CliError::internal)?,
        ),
        None => None,
    };
    Ok(Executed {
        spec: e.spec_path.display().to_string(),
        report_file: written(e.report),
        trace_file: written(e.trace.filter(|_| trace_trial.is_some())),
        trace_trial,
        report,
    })
}

/// The causes seen in failed trials besides their root cause, e.g. `slipped 3, goal not met 5`
/// (`none` if none).
fn secondary(r: &BatchReport) -> String {
    let seen: Vec<String> = r
        .secondary
        .iter()
        .map(|(cause, n)| format!("{cause} {n}"))
        .collect();
    if seen.is_empty() {
        "none".into()
    } else {
        seen.join(", ")
    }
}

fn millimetres(metres: Option<f64>) -> String {
    metres.map_or_else(|| "- (no lines)".into(), |m| format!("{:.3} mm", m * 1e3))
}

/// Prints the summary table and the failed trials.
pub(crate) fn print_executed(x: &Executed) {
    let r = &x.report;
    let placement = if r.randomized {
        format!("{} randomized trials (seeds {}..)", r.trials, r.seed)
    } else {
        format!("{} trial(s) with the task's placements", r.trials)
    };
    println!(
        "{}: {} spec on task `{}`, {placement}, {} in parallel",
        x.spec, r.method, r.task, r.jobs
    );
    if r.interrupted {
        println!(
            "interrupted: only the {} trials that finished are counted",
            r.trials
        );
    }
    let trials = r.trials.to_string();
    let mut table = Table::new(["trials", &trials]);
    let mut row = |a: &str, b: String| table.row(vec![a.to_string(), b]);
    row("passed", r.pass_rate.to_string());
    for cause in Cause::ALL {
        let n = r.failures.get(&cause).copied().unwrap_or(0);
        row(&format!("failed: {cause}"), n.to_string());
    }
    row("also seen (not root)", secondary(r));
    row("worst line deviation", millimetres(r.worst_line_deviation));
    let worst = |f: &dyn Fn(&akl_exec::report::TrialReport) -> f64| {
        r.reports.iter().map(f).fold(0.0, f64::max)
    };
    row(
        "worst tracking error",
        format!("{:.2} mm", worst(&|t| t.tracking.max) * 1e3),
    );
    row(
        "deepest contact",
        format!("{:.2} mm", worst(&|t| t.deepest_contact.value) * 1e3),
    );
    row(
        "largest contact force",
        format!("{:.1} N", worst(&|t| t.largest_force.value)),
    );
    row(
        "perception noise (σ)",
        format!(
            "{:.1} mm, {:.1}°",
            r.settings.pose_noise_position * 1e3,
            r.settings.pose_noise_yaw.to_degrees()
        ),
    );
    row(
        "time per trial",
        format!(
            "{:.3} s (planning {:.3} s, simulation {:.3} s)",
            r.seconds_per_trial, r.plan_seconds_per_trial, r.sim_seconds_per_trial
        ),
    );
    row(
        "wall time",
        format!(
            "{:.2} s ({:.1} trials/s)",
            r.wall_seconds,
            r.trials as f64 / r.wall_seconds.max(1e-9)
        ),
    );
    print!("{}", table.render());
    let failed: Vec<_> = r.reports.iter().filter(|t| !t.passed).collect();
    if !failed.is_empty() {
        println!("failed trials (root cause first):");
        for t in failed.iter().take(LISTED_FAILURES) {
            let first = t
                .root()
                .map_or(String::new(), |f| format!("{}: {}", f.cause, f.detail));
            let more = match t.failures.len() {
                0 | 1 => String::new(),
                n => format!(" (and {} more)", n - 1),
            };
            println!("  trial {} (seed {}): {first}{more}", t.trial, t.seed);
        }
        if failed.len() > LISTED_FAILURES {
            println!("  ... {} more", failed.len() - LISTED_FAILURES);
        }
    }
}

/// Prints where the report and trace went.
fn print_outputs(x: &Executed) {
    if let Some(f) = &x.report_file {
        println!("report: {f}");
    }
    if let (Some(f), Some(i)) = (&x.trace_file, x.trace_trial) {
        println!("trace of trial {i}: {f}");
    }
}
