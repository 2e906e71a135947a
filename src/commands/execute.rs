//! `akl execute SPEC --task T`, and the execution stage of `akl demo`.

use super::robot::load as load_robot;
use super::{check_output, print_json};
use crate::cli::{ExecuteArgs, Goals, PoseNoiseArg};
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::batch::{identity, Batch, BatchOptions};
use akl_exec::merge::{self, StoredReport};
use akl_exec::report::{BatchReport, Cause, StoredTrial, TrialOutcome, TrialReport};
use akl_exec::{junit, ExecError, ExecOptions, PoseNoise, Setup, Shard, Suite};
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

/// What `akl execute` adds to an [`Execution`]: a shard of the run, a run to finish.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Sharding<'a> {
    /// Run only this shard's trials.
    pub shard: Option<Shard>,
    /// The report of the interrupted run to finish.
    pub resume: Option<&'a Path>,
}

/// The outcome of an execution, as `--json` prints it.
#[derive(Serialize)]
pub(crate) struct Executed<T = TrialReport> {
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
    pub report: BatchReport<T>,
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
    let shard = match args.shard {
        Some(request) => Some(
            request
                .resolve(|name| std::env::var(name).ok())
                .map_err(CliError::input)?,
        ),
        None => None,
    };
    if let Some(p) = &args.junit {
        check_output(p, "JUnit file")?;
    }
    let execution = Execution {
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
        report: args.report.as_deref().or(args.resume.as_deref()),
    };
    let sharding = Sharding {
        shard,
        resume: args.resume.as_deref(),
    };
    let (executed, expected) = execute_sharded(&execution, sharding)?;
    if let Some(p) = &args.junit {
        let name = format!("{} on {}", args.spec.display(), task.name);
        let class = format!("akl.{}", task.name);
        let mut properties = Vec::new();
        if let Some(s) = executed.report.shard {
            properties.push(("shard".to_string(), s.to_string()));
        }
        let suite = Suite {
            name: &name,
            class: &class,
            properties,
        };
        akl_tsr::io::write_atomic(p, junit(&executed.report, &suite).as_bytes())
            .map_err(|e| CliError::internal(format!("{}: {e}", p.display())))?;
    }
    if args.json {
        print_json(&executed)?;
    } else {
        print_executed(&executed);
        print_outputs(&executed);
        if let Some(p) = &args.junit {
            println!("JUnit: {}", p.display());
        }
    }
    if executed.report.interrupted {
        return Err(CliError::interrupted(format!(
            "interrupted: {} of {expected} trials finished",
            executed.report.trials,
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
pub(crate) fn verdict<T: TrialOutcome>(report: &BatchReport<T>) -> CliResult {
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
    let trials = check_execution(e)?;
    let batch = make_batch(e, trials, None, None)?;
    let report = run_batch(e, &batch)?;
    let written = |p: Option<&Path>| p.map(|p| p.display().to_string());
    if let Some(p) = e.report {
        report
            .save(p)
            .map_err(|err| CliError::internal(format!("{}: {err}", p.display())))?;
    }
    let trace_trial = write_trace(e, &batch, &report)?;
    Ok(Executed {
        spec: e.spec_path.display().to_string(),
        report_file: written(e.report),
        trace_file: written(e.trace.filter(|_| trace_trial.is_some())),
        trace_trial,
        report,
    })
}

/// [`execute`] for `akl execute`: only the trials of `sharding.shard` when given, and, when
/// `sharding.resume` names an interrupted run's report, only the trials it lacks, joined to
/// those it kept. Returns the execution and the number of trials it should hold.
fn execute_sharded(
    e: &Execution,
    sharding: Sharding,
) -> Result<(Executed<StoredTrial>, usize), CliError> {
    let trials = check_execution(e)?;
    let stored = |r: &BatchReport| r.stored().map_err(CliError::internal);
    let written = |p: Option<&Path>| p.map(|p| p.display().to_string());
    let (report, trace_trial) = match sharding.resume {
        None => {
            let batch = make_batch(e, trials, sharding.shard, None)?;
            let report = run_batch(e, &batch)?;
            let trace_trial = write_trace(e, &batch, &report)?;
            (stored(&report)?, trace_trial)
        }
        Some(path) => (resume(e, trials, sharding.shard, path)?, None),
    };
    if let Some(p) = e.report {
        report
            .save(p)
            .map_err(|err| CliError::internal(format!("{}: {err}", p.display())))?;
    }
    let expected = sharding.shard.map_or(trials, |s| s.trials(trials).len());
    Ok((
        Executed {
            spec: e.spec_path.display().to_string(),
            report_file: written(e.report),
            trace_file: written(e.trace.filter(|_| trace_trial.is_some())),
            trace_trial,
            report,
        },
        expected,
    ))
}

/// Finishes the interrupted run whose report is `path`: the trials it lacks are run and
/// joined to those it kept.
fn resume(
    e: &Execution,
    trials: usize,
    shard: Option<Shard>,
    path: &Path,
) -> Result<StoredReport, CliError> {
    let kept = merge::read(path).map_err(CliError::input)?;
    let setup = Setup {
        robot: e.robot,
        task: e.task,
        spec: e.spec,
        options: &e.options,
    };
    let missing = merge::check_resume(
        path,
        &kept,
        &identity(&setup, trials),
        e.seed,
        e.randomize.is_some(),
        shard,
    )
    .map_err(CliError::input)?;
    if missing.is_empty() {
        let mut whole = kept;
        whole.interrupted = false;
        return Ok(whole);
    }
    let batch = make_batch(e, trials, shard, Some(missing))?;
    let more = run_batch(e, &batch)?;
    merge::resume(path, &kept, &more).map_err(CliError::input)
}

/// Checks `e`'s outputs and trial counts before any work; returns the run's trials.
fn check_execution(e: &Execution) -> Result<usize, CliError> {
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
    jobs(e.jobs)?;
    if let Some(i) = e.trace_trial.filter(|&i| i >= trials) {
        return Err(CliError::input(format!(
            "--trace-trial {i}: there are only {trials} trials (0 to {})",
            trials - 1
        )));
    }
    Ok(trials)
}

/// The batch of `e`'s run of `trials`: all of them, shard `shard`'s, or only `only` (of
/// shard `shard`, if given).
fn make_batch<'a>(
    e: &'a Execution,
    trials: usize,
    shard: Option<Shard>,
    only: Option<Vec<usize>>,
) -> Result<Batch<'a>, CliError> {
    let count = match (&only, shard) {
        (Some(only), _) => only.len(),
        (None, Some(s)) => s.trials(trials).len(),
        (None, None) => trials,
    };
    let options = BatchOptions {
        trials,
        randomize: e.randomize.is_some(),
        seed: e.seed,
        jobs: jobs(e.jobs)?.min(count.max(1)),
    };
    let setup = Setup {
        robot: e.robot,
        task: e.task,
        spec: e.spec,
        options: &e.options,
    };
    let batch = match (only, shard) {
        (Some(only), shard) => Batch::only(setup, options, shard, only),
        (None, Some(shard)) => Batch::shard(setup, options, shard),
        (None, None) => Batch::new(e.robot, e.task, e.spec, &e.options, options),
    };
    if let (Some(i), Ok(b)) = (e.trace_trial, &batch) {
        if b.world(i).is_none() {
            return Err(CliError::input(format!(
                "--trace-trial {i}: not a trial of this shard (it runs trials {} to {})",
                b.indices()[0],
                b.indices()[b.indices().len() - 1]
            )));
        }
    }
    batch.map_err(|err| match err {
        ExecError::Spec(source) => CliError::input(FileError {
            path: e.spec_path.to_path_buf(),
            source,
        }),
        ExecError::Scene(source) => CliError::input(format!("task `{}`: {source}", e.task.name)),
        other => CliError::input(other),
    })
}

/// Runs `batch`, showing progress.
fn run_batch(e: &Execution, batch: &Batch) -> Result<BatchReport, CliError> {
    let progress = Progress::new(
        &format!("executing on `{}`", e.task.name),
        batch.indices().len(),
    );
    let report = batch
        .run(&|r| progress.tick(r.passed))
        .map_err(CliError::internal);
    progress.finish();
    report
}

/// Writes the trace `e` asks for, unless the run was interrupted; returns the trial shown.
fn write_trace(
    e: &Execution,
    batch: &Batch,
    report: &BatchReport,
) -> Result<Option<usize>, CliError> {
    match e.trace.filter(|_| !report.interrupted) {
        Some(p) => Ok(Some(
            batch
                .write_trace(report, e.trace_trial, p)
                .map_err(CliError::internal)?,
        )),
        None => Ok(None),
    }
}

/// The causes seen in failed trials besides their root cause, e.g. `slipped 3, goal not met 5`
/// (`none` if none).
fn secondary<T>(r: &BatchReport<T>) -> String {
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
pub(crate) fn print_executed<T: TrialOutcome>(x: &Executed<T>) {
    let r = &x.report;
    let placement = match (r.randomized, r.shard) {
        (true, Some(s)) => {
            let first = r.reports.first().map_or(0, |t| t.index());
            format!(
                "shard {s}: {} randomized trials (trials {first}.., seeds {}..)",
                r.trials,
                r.seed + first as u64
            )
        }
        (true, None) => format!("{} randomized trials (seeds {}..)", r.trials, r.seed),
        (false, _) => format!("{} trial(s) with the task's placements", r.trials),
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
    let worst = |k: usize| {
        r.reports
            .iter()
            .map(|t| t.extremes()[k])
            .fold(0.0, f64::max)
    };
    row("worst tracking error", format!("{:.2} mm", worst(0) * 1e3));
    row("deepest contact", format!("{:.2} mm", worst(1) * 1e3));
    row("largest contact force", format!("{:.1} N", worst(2)));
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
            "{:.1} ms (planning {:.1} ms, simulation {:.1} ms)",
            r.seconds_per_trial * 1e3,
            r.plan_seconds_per_trial * 1e3,
            r.sim_seconds_per_trial * 1e3
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
    let failed: Vec<_> = r.reports.iter().filter(|t| !t.passed()).collect();
    if !failed.is_empty() {
        println!("failed trials (root cause first):");
        for t in failed.iter().take(LISTED_FAILURES) {
            let list = t.failure_list();
            let first = list.first().map_or(String::new(), |(cause, detail)| {
                format!("{cause}: {detail}")
            });
            let more = match list.len() {
                0 | 1 => String::new(),
                n => format!(" (and {} more)", n - 1),
            };
            println!("  trial {} (seed {}): {first}{more}", t.index(), t.seed());
        }
        if failed.len() > LISTED_FAILURES {
            println!("  ... {} more", failed.len() - LISTED_FAILURES);
        }
    }
}

/// Prints where the report and trace went.
fn print_outputs<T>(x: &Executed<T>) {
    if let Some(f) = &x.report_file {
        println!("report: {f}");
    }
    if let (Some(f), Some(i)) = (&x.trace_file, x.trace_trial) {
        println!("trace of trial {i}: {f}");
    }
}
