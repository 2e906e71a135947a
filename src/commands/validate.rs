//! `akl validate SPEC --task T`: the deployment gate.

use super::execute::{jobs, pose_noise};
use super::robot::load as load_robot;
use super::{check_output, load_calibration, load_spec_for, print_json};
use crate::cli::{GateArgs, TrialArgs, ValidateArgs};
use crate::exit::{CliError, CliResult, NOT_MINIMAL, UNDECIDED};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::batch::{identity, settings, Batch, BatchOptions};
use akl_exec::merge;
use akl_exec::report::{BatchReport, TrialOutcome};
use akl_exec::{junit, ExecError, ExecOptions, Setup, Suite};
use akl_learn::okl::OklParams;
use akl_learn::{read_demo_file, Demo, LearnOptions};
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate, GateOptions, GateVerdict};
use akl_tsr::TaskSpec;
use akl_validate::ablation::Ablation;
use akl_validate::answers::{AnswerVerdict, Answers, DemoSource};
use akl_validate::trials::verifying;
use akl_validate::validation::Stage;
use akl_validate::{validate, Outcome, ValidateError, ValidateOptions, Validation, Verdict};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// How many failed trials the text lists, each with its replay command.
const LISTED_FAILURES: usize = 10;

#[derive(Serialize)]
struct Validated<'a> {
    /// The spec's file (`spec` holds its gated trials).
    spec_file: String,
    speed_scale: f64,
    task: String,
    demo: Option<String>,
    report_file: Option<String>,
    trace_file: Option<String>,
    /// The command that replays each failed trial of the spec.
    replays: Vec<Replay>,
    #[serde(flatten)]
    validation: &'a Validation,
}

/// A failed trial of the spec and how to see it again.
#[derive(Serialize)]
struct Replay {
    seed: u64,
    command: String,
}

/// The gate `--min-success`, `--confidence` and `--max-trials` ask for, `default_max` trials
/// at most unless told (checked: bad values exit 2).
pub(crate) fn gate_options(args: &GateArgs, default_max: usize) -> Result<GateOptions, CliError> {
    let options = GateOptions {
        min_success: args.min_success,
        confidence: args.confidence,
        max_trials: args.max_trials.unwrap_or(default_max),
    };
    Gate::new(options).map_err(CliError::input)?;
    Ok(options)
}

/// Execution settings from `--pose-noise` and `--speed-scale`, stopped by Ctrl-C.
pub(crate) fn exec_options(args: &TrialArgs) -> ExecOptions {
    let mut options = ExecOptions {
        noise: pose_noise(args.pose_noise),
        interrupt: crate::stop::interrupt(),
        ..ExecOptions::default()
    };
    options.plan.speed_scale = args.speed.speed_scale;
    options
}

/// A library error as the CLI reports it: what the input got wrong (naming the spec file or
/// the task) exits 2, anything else 1.
pub(crate) fn cli_error(e: ValidateError, spec: &Path, task: &Task) -> CliError {
    match e {
        ValidateError::Exec(ExecError::Spec(source)) => CliError::input(akl_tsr::FileError {
            path: spec.to_path_buf(),
            source,
        }),
        ValidateError::Exec(ExecError::Scene(source)) => {
            CliError::input(format!("task `{}`: {source}", task.name))
        }
        ValidateError::Exec(ExecError::Options(m)) | ValidateError::Options(m) => {
            CliError::input(m)
        }
        other => CliError::internal(other),
    }
}

fn read_demo(path: &Path, task: &Task) -> Result<Demo, CliError> {
    let loaded = read_demo_file(path).map_err(CliError::input)?;
    if let Some(t) = &loaded.truncation {
        eprintln!("warning: {}: {t}", path.display());
    }
    let demo = loaded.demo;
    if demo.header.task != task.name {
        return Err(CliError::input(format!(
            "{}: a demonstration of task `{}`, not of `{}`",
            path.display(),
            demo.header.task,
            task.name
        )));
    }
    if demo.detector.is_empty() {
        return Err(CliError::input(format!(
            "{}: {}",
            path.display(),
            ValidateError::NoDetector
        )));
    }
    Ok(demo)
}

/// The `akl execute` command that replays the validation trial of `seed`.
fn replay_command(args: &ValidateArgs, seed: u64) -> String {
    let mut command = format!(
        "akl execute {} --task {} --seed {seed} --randomize 1 --goals sampled",
        args.spec.display(),
        args.task
    );
    let noise = args.trials.pose_noise;
    if (noise.millimetres, noise.degrees) != (2.0, 1.0) {
        command += &format!(" --pose-noise {},{}", noise.millimetres, noise.degrees);
    }
    if let Some(robot) = &args.robot.robot {
        command += &format!(" --robot {}", robot.display());
    }
    command + &format!(" --trace trial-{seed}.mcap")
}

pub(super) fn run(args: ValidateArgs) -> CliResult {
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let spec = load_spec_for(&args.spec, &task, args.fit)?;
    if let Some(p) = &args.junit {
        check_output(p, "JUnit file")?;
    }
    if let Some(report) = &args.from_report {
        return from_report(&args, &robot, &task, &spec, report);
    }
    for (path, what) in [(&args.report, "report"), (&args.trace, "trace")] {
        if let Some(p) = path {
            check_output(p, what)?;
        }
    }
    let options = ValidateOptions {
        seed: args.seed,
        jobs: jobs(args.trials.jobs)?,
        gate: gate_options(&args.gate, GateOptions::default().max_trials)?,
        exec: exec_options(&args.trials),
    };
    let demo = match &args.demo {
        Some(p) => Some(read_demo(p, &task)?),
        None => None,
    };
    let (calibration, _) = load_calibration(args.calibration.as_deref())?;
    let learn = LearnOptions {
        okl: OklParams::for_calibration(&calibration),
        ..LearnOptions::default()
    };
    let source = demo.as_ref().map(|demo| DemoSource {
        demo,
        calibration: &calibration,
        learn: &learn,
    });
    let removals = akl_validate::ablation::removals(&spec).len();
    let progress = Progress::new(
        &format!("validating on `{}`", task.name),
        options.gate.max_trials,
    );
    let started = Instant::now();
    let validation = validate(
        &robot,
        &task,
        &spec,
        &options,
        source,
        &|stage, n| match stage {
            Stage::Spec => progress.set(n),
            Stage::Removal(done) => progress.relabel(&format!("removal {done} of {removals}")),
            Stage::Answer(done) => progress.relabel(&format!("answer {done}")),
        },
    );
    progress.finish();
    let validation = validation.map_err(|e| match (e, &args.demo) {
        (
            e @ (ValidateError::Learn(_) | ValidateError::Replay(_) | ValidateError::NoDetector),
            Some(p),
        ) => CliError::input(format!("{}: {e}", p.display())),
        (e, _) => cli_error(e, &args.spec, &task),
    })?;
    let wall = started.elapsed().as_secs_f64();
    let report_file = match &args.report {
        Some(p) => {
            let report = spec_report(&robot, &task, &spec, &options, &validation, wall);
            report
                .save(p)
                .map_err(|e| CliError::internal(format!("{}: {e}", p.display())))?;
            Some(p.display().to_string())
        }
        None => None,
    };
    let trace_file = match &args.trace {
        Some(p) if !validation.interrupted => {
            write_trace(
                &robot,
                &task,
                &spec,
                &options,
                &validation,
                args.trace_trial,
                p,
            )?;
            Some(p.display().to_string())
        }
        _ => None,
    };
    let replays = validation
        .spec
        .outcome
        .failed_seeds
        .iter()
        .map(|&seed| Replay {
            seed,
            command: replay_command(&args, seed),
        })
        .collect();
    let validated = Validated {
        spec_file: args.spec.display().to_string(),
        speed_scale: args.trials.speed.speed_scale,
        task: task.name.clone(),
        demo: args.demo.as_ref().map(|p| p.display().to_string()),
        report_file,
        trace_file,
        replays,
        validation: &validation,
    };
    if let Some(p) = &args.junit {
        let report = spec_report(&robot, &task, &spec, &options, &validation, wall);
        write_junit(&args, &task, &report, p)?;
    }
    if args.json {
        print_json(&validated)?;
    } else {
        print_validation(&args, &task, &validated);
    }
    let name = args.spec.display();
    match validation.verdict {
        Some(Verdict::Passes) => Ok(()),
        Some(Verdict::Fails) => Err(CliError::internal(format!("{name}: fails"))),
        Some(Verdict::Undecided) => Err(CliError::verdict(
            UNDECIDED,
            format!(
                "{name}: undecided within {} trials",
                options.gate.max_trials
            ),
        )),
        Some(Verdict::NotMinimal) => Err(CliError::verdict(
            NOT_MINIMAL,
            format!("{name}: not minimal"),
        )),
        None => Err(CliError::interrupted(format!(
            "interrupted: {} trials of the spec judged",
            validation.spec.outcome.run
        ))),
    }
}

/// Writes `report`'s trials (those the gate read) as JUnit XML to `path`, the gate's
/// question and decision as properties.
fn write_junit<T: TrialOutcome>(
    args: &ValidateArgs,
    task: &Task,
    report: &BatchReport<T>,
    path: &Path,
) -> CliResult {
    let name = format!("{} on {}", args.spec.display(), task.name);
    let class = format!("akl.{}", task.name);
    let mut properties = Vec::new();
    if let Some(g) = report.gate {
        properties.push(("min_success".to_string(), g.options.min_success.to_string()));
        properties.push(("confidence".to_string(), g.options.confidence.to_string()));
        properties.push(("max_trials".to_string(), g.options.max_trials.to_string()));
        properties.push((
            "decision".to_string(),
            g.decision
                .map_or("none (interrupted)", |d| d.label())
                .to_string(),
        ));
    }
    let suite = Suite {
        name: &name,
        class: &class,
        properties,
    };
    akl_tsr::io::write_atomic(path, junit(report, &suite).as_bytes())
        .map_err(|e| CliError::internal(format!("{}: {e}", path.display())))?;
    Ok(())
}

/// What `akl validate --from-report --json` prints.
#[derive(Serialize)]
struct FromReport {
    spec_file: String,
    report_file: String,
    task: String,
    seed: u64,
    gate: GateOptions,
    /// `None` when the report's trials run out before the gate decides.
    decision: Option<Decision>,
    /// Trials the gate read (in seed order, up to its decision).
    trials_read: usize,
    /// Trials the report holds.
    trials_in_report: usize,
    pass_rate: akl_stats::PassRate,
    failed_seeds: Vec<u64>,
    replays: Vec<Replay>,
}

/// `akl validate SPEC --task T --from-report FILE`: the gate over the report's trials in
/// seed order, no trial run.
fn from_report(
    args: &ValidateArgs,
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    path: &Path,
) -> CliResult {
    let options = gate_options(&args.gate, GateOptions::default().max_trials)?;
    let gate = Gate::new(options).map_err(CliError::input)?;
    let mut report = merge::read(path).map_err(CliError::input)?;
    let theirs = report
        .identity
        .clone()
        .ok_or_else(|| CliError::input(merge::MergeError::NoIdentity { path: path.into() }))?;
    let exec = verifying(&exec_options(&args.trials));
    let setup = Setup {
        robot,
        task,
        spec,
        options: &exec,
    };
    let ours = identity(&setup, theirs.trials);
    let refuse = |what: &str| {
        CliError::input(format!(
            "{}: the report's trials were not run {what}",
            path.display()
        ))
    };
    if ours.spec_hash != theirs.spec_hash {
        return Err(refuse(&format!("with {}", args.spec.display())));
    }
    if ours.task_hash != theirs.task_hash {
        return Err(refuse(&format!("on task `{}`", args.task)));
    }
    if ours.robot_hash != theirs.robot_hash {
        return Err(refuse("with this robot"));
    }
    if ours.version != theirs.version {
        return Err(refuse(&format!(
            "by this akl (version {}, theirs {})",
            ours.version, theirs.version
        )));
    }
    if ours.settings_hash != theirs.settings_hash || !report.randomized {
        return Err(refuse(
            "as validation runs them: run `akl execute --randomize N --goals sampled` with the \
             same --pose-noise and --speed-scale as this validate",
        ));
    }
    if report.shard.is_some() {
        return Err(refuse(
            "as one whole run: it is one shard; merge the shards with `akl report merge` first",
        ));
    }
    if let Some(gap) = report
        .reports
        .iter()
        .enumerate()
        .find(|(k, t)| t.index() != *k)
    {
        return Err(refuse(&format!(
            "in an unbroken sequence: trial {} is missing (finish the run with `akl execute ... \
             --resume {}`)",
            gap.0,
            path.display()
        )));
    }
    let judged = gate.judge(report.reports.iter().map(TrialOutcome::passed));
    let (decision, read) = match judged {
        Some((d, n)) => (Some(d), n),
        None => (None, report.reports.len()),
    };
    report.reports.truncate(read);
    let failed_seeds: Vec<u64> = report
        .reports
        .iter()
        .filter(|t| !t.passed())
        .map(TrialOutcome::seed)
        .collect();
    let passed = read - failed_seeds.len();
    let pass_rate = akl_stats::PassRate::new(passed, read);
    if let Some(p) = &args.junit {
        let mut gated = BatchReport::new(
            &report.task,
            &report.method,
            report.seed,
            true,
            report.reports.clone(),
            report.jobs,
            report.wall_seconds,
            report.settings.clone(),
        );
        gated.gate = Some(GateVerdict { options, decision });
        write_junit(args, task, &gated, p)?;
    }
    let replays: Vec<Replay> = failed_seeds
        .iter()
        .map(|&seed| Replay {
            seed,
            command: replay_command(args, seed),
        })
        .collect();
    let out = FromReport {
        spec_file: args.spec.display().to_string(),
        report_file: path.display().to_string(),
        task: task.name.clone(),
        seed: report.seed,
        gate: options,
        decision,
        trials_read: read,
        trials_in_report: report.trials,
        pass_rate,
        failed_seeds,
        replays,
    };
    if args.json {
        print_json(&out)?;
    } else {
        print_from_report(&out);
    }
    let name = args.spec.display();
    match decision {
        Some(Decision::Passes) => Ok(()),
        Some(Decision::Fails) => Err(CliError::internal(format!("{name}: fails"))),
        Some(Decision::Undecided) => Err(CliError::verdict(
            UNDECIDED,
            format!("{name}: undecided within {} trials", options.max_trials),
        )),
        None => Err(CliError::verdict(
            UNDECIDED,
            format!(
                "{name}: undecided: the report's {} trials are too few for the gate to decide",
                out.trials_in_report
            ),
        )),
    }
}

fn print_from_report(x: &FromReport) {
    println!(
        "{} on task `{}`: does it succeed with probability at least {} at {:.0} % confidence? \
         The trials of {} (seeds {}.., {} trials), judged in seed order (removals and answers \
         are not judged from a report)",
        x.spec_file,
        x.task,
        x.gate.min_success,
        100.0 * x.gate.confidence,
        x.report_file,
        x.seed,
        x.trials_in_report
    );
    let decision = x.decision.map_or_else(
        || "undecided (the report holds too few trials)".to_string(),
        |d| d.label().to_string(),
    );
    println!("spec: {decision} — passed {}", x.pass_rate);
    if !x.replays.is_empty() {
        println!("failed trials, and how to replay each:");
        for r in x.replays.iter().take(LISTED_FAILURES) {
            println!("  seed {}: {}", r.seed, r.command);
        }
        if x.replays.len() > LISTED_FAILURES {
            println!("  ... {} more", x.replays.len() - LISTED_FAILURES);
        }
    }
}

/// The spec's trials as a report in `akl execute --report`'s format, with the gate.
fn spec_report(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &ValidateOptions,
    validation: &Validation,
    wall: f64,
) -> BatchReport {
    let mut report = BatchReport::new(
        &task.name,
        &spec.method,
        options.seed,
        true,
        validation.spec.reports.clone(),
        options.jobs,
        wall,
        settings(robot, &verifying(&options.exec), spec),
    );
    report.gate = Some(GateVerdict {
        options: options.gate,
        decision: validation.spec.decision,
    });
    report.interrupted = validation.interrupted;
    report
}

/// Writes trial `trial` of the spec's trials (default: the first that failed, else the first)
/// as an MCAP trace.
fn write_trace(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &ValidateOptions,
    validation: &Validation,
    trial: Option<usize>,
    path: &Path,
) -> CliResult {
    let outcome = &validation.spec.outcome;
    let i = match trial {
        Some(i) if i >= outcome.run => {
            return Err(CliError::input(format!(
                "--trace-trial {i}: the gate read only {} trials (0 to {})",
                outcome.run,
                outcome.run.saturating_sub(1)
            )))
        }
        Some(i) => i,
        None => outcome
            .failed_seeds
            .first()
            .map_or(0, |s| (s - options.seed) as usize),
    };
    let exec = verifying(&options.exec);
    let batch = Batch::new(
        robot,
        task,
        spec,
        &exec,
        BatchOptions {
            trials: 1,
            randomize: true,
            seed: options.seed + i as u64,
            jobs: 1,
        },
    )
    .map_err(CliError::internal)?;
    let one = batch.run(&|_| {}).map_err(CliError::internal)?;
    batch
        .write_trace(&one, Some(0), path)
        .map_err(|e| CliError::internal(format!("{}: {e}", path.display())))?;
    Ok(())
}

/// `passed/run (rate, 95 % CI)`.
fn passed_of(o: &Outcome) -> String {
    o.pass_rate.to_string()
}

fn first_cause(o: &Outcome) -> String {
    o.first_failure
        .as_ref()
        .map_or("-".into(), |f| f.cause.to_string())
}

fn removal_row(a: &Ablation) -> Vec<String> {
    let (trials, why) = match (&a.outcome, &a.invalid) {
        (Some(o), _) => (passed_of(o), first_cause(o)),
        (None, Some(why)) => ("-".into(), format!("not a spec: {why}")),
        (None, None) => ("-".into(), "-".into()),
    };
    let gate = a.decision.map_or("-", |d| d.label());
    vec![
        a.what.clone(),
        trials,
        gate.into(),
        a.essential.label().into(),
        why,
    ]
}

fn print_answers(demo: &Path, answers: &Answers) {
    println!(
        "answers of {} (the spec AKL learns from it {} the spec validated; it has {} line(s) and {} the gate, {}):",
        demo.display(),
        if answers.spec_is_learned_from_demo {
            "is"
        } else {
            "is not"
        },
        answers.lines,
        answers.baseline_decision.map_or("was not judged by", |d| d.label()),
        passed_of(&answers.baseline),
    );
    if answers.checks.is_empty() {
        println!("  the demonstration holds no answers");
        return;
    }
    let mut table = Table::new([
        "  answer",
        "t (s)",
        "given",
        "flipped to",
        "lines then",
        "gate then",
        "verdict",
    ]);
    for c in &answers.checks {
        let verdict = match c.verdict {
            AnswerVerdict::Contradicted => {
                if c.answer == akl_learn::Answer::No {
                    "CONTRADICTED: the line is needed"
                } else {
                    "CONTRADICTED: the line can be dropped"
                }
            }
            AnswerVerdict::Confirmed => "confirmed",
            AnswerVerdict::Undecided => "undecided: the gates cannot tell",
            AnswerVerdict::Unchanged => "unchanged: the flip learns the same spec",
        };
        let then = match (&c.decision, &c.outcome) {
            (Some(d), Some(o)) => format!("{} ({}/{})", d.label(), o.passed, o.run),
            _ => "-".into(),
        };
        table.row(vec![
            format!("  {}", c.index),
            format!("{:.2}", c.t),
            format!("{:?}", c.answer).to_lowercase(),
            format!("{:?}", c.flipped_to).to_lowercase(),
            c.lines_when_flipped.to_string(),
            then,
            verdict.into(),
        ]);
    }
    print!("{}", table.render());
}

fn print_validation(args: &ValidateArgs, task: &Task, x: &Validated) {
    let v = x.validation;
    let g = &v.gate;
    println!(
        "{} on task `{}`: does it succeed with probability at least {} at {:.0} % confidence? \
         Randomized trials from seed {} (at most {}), goals drawn across every TSR",
        args.spec.display(),
        task.name,
        g.min_success,
        100.0 * g.confidence,
        v.seed,
        g.max_trials
    );
    let o = &v.spec.outcome;
    let causes: Vec<String> = o.failures.iter().map(|(c, k)| format!("{c} {k}")).collect();
    println!(
        "spec: {} — passed {}{}",
        v.spec.decision.map_or("interrupted", |d| d.label()),
        passed_of(o),
        if causes.is_empty() {
            String::new()
        } else {
            format!("; failed by root cause: {}", causes.join(", "))
        }
    );
    if !x.replays.is_empty() {
        println!("failed trials, and how to replay each:");
        for r in x.replays.iter().take(LISTED_FAILURES) {
            println!("  seed {}: {}", r.seed, r.command);
        }
        if x.replays.len() > LISTED_FAILURES {
            println!("  ... {} more", x.replays.len() - LISTED_FAILURES);
        }
        if let Some(f) = o.first_failure_text() {
            println!("  first failure: {f}");
        }
    }
    if !v.removals.is_empty() {
        println!("without each keyframe and each line, judged by the same gate on the same seeds:");
        let mut table = Table::new(["  removed", "passed", "gate", "essential", "first failure"]);
        for a in &v.removals {
            let mut row = removal_row(a);
            row[0] = format!("  {}", row[0]);
            table.row(row);
        }
        print!("{}", table.render());
    }
    if let (Some(answers), Some(demo)) = (&v.answers, &args.demo) {
        print_answers(demo, answers);
    }
    for (file, what) in [(&x.report_file, "report"), (&x.trace_file, "trace")] {
        if let Some(f) = file {
            println!("{what}: {f}");
        }
    }
    if v.interrupted {
        println!("interrupted: only what finished is listed");
    }
    let superfluous: Vec<&str> = v.not_essential().map(|a| a.what.as_str()).collect();
    let mut reasons = Vec::new();
    if !superfluous.is_empty() {
        reasons.push(format!(
            "not essential: {} (the spec passes the gate without it)",
            superfluous.join(", ")
        ));
    }
    let contradicted = v.contradicted().count();
    if contradicted > 0 {
        reasons.push(format!("{contradicted} answer(s) contradicted"));
    }
    println!(
        "verdict: {}{}",
        v.verdict.map_or("none (interrupted)", |v| v.label()),
        if reasons.is_empty() {
            String::new()
        } else {
            format!(" — {}", reasons.join("; "))
        }
    );
}
