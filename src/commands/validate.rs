//! `akl validate SPEC --task T`: the deployment gate.

use super::execute::{jobs, pose_noise};
use super::robot::load as load_robot;
use super::{load_calibration, load_spec_for, print_json};
use crate::cli::{TrialArgs, ValidateArgs};
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::error::ExecError;
use akl_exec::trial::ExecOptions;
use akl_learn::okl::OklParams;
use akl_learn::recording::read_demo_file;
use akl_learn::{Demo, LearnOptions};
use akl_scene::{builtin, Task};
use akl_validate::ablation::Ablation;
use akl_validate::answers::{AnswerVerdict, Answers, DemoSource};
use akl_validate::{
    validate, Outcome, Trials, ValidateError, ValidateOptions, Validation, Verdict,
};
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Validated<'a> {
    spec: String,
    task: String,
    demo: Option<String>,
    #[serde(flatten)]
    validation: &'a Validation,
}

/// The trials `--randomize N --seed S --jobs J` ask for.
pub(crate) fn trials(count: usize, seed: u64, args: &TrialArgs) -> Result<Trials, CliError> {
    if count == 0 {
        return Err(CliError::input("--randomize: needs at least one trial"));
    }
    Ok(Trials {
        count,
        seed,
        jobs: jobs(args.jobs)?,
    })
}

/// Execution settings from `--pose-noise`.
pub(crate) fn exec_options(args: &TrialArgs) -> ExecOptions {
    ExecOptions {
        noise: pose_noise(args.pose_noise),
        ..ExecOptions::default()
    }
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

pub fn run(args: ValidateArgs) -> CliResult {
    let robot = load_robot(&args.robot)?;
    let task = builtin::resolve(&args.task).map_err(CliError::input)?;
    let spec = load_spec_for(&args.spec, &task)?;
    let options = ValidateOptions {
        trials: trials(args.randomize, args.seed, &args.trials)?,
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
    let checks = 1 + akl_validate::ablation::removals(&spec).len();
    let progress = Progress::new(
        &format!("validating on `{}`", task.name),
        checks * args.randomize,
    );
    let validation = validate(&robot, &task, &spec, &options, source, &|done, _| {
        progress.set(done * args.randomize)
    });
    progress.finish();
    let validation = validation.map_err(|e| match (e, &args.demo) {
        (
            e @ (ValidateError::Learn(_) | ValidateError::Replay(_) | ValidateError::NoDetector),
            Some(p),
        ) => CliError::input(format!("{}: {e}", p.display())),
        (e, _) => cli_error(e, &args.spec, &task),
    })?;
    if args.json {
        print_json(&Validated {
            spec: args.spec.display().to_string(),
            task: task.name.clone(),
            demo: args.demo.as_ref().map(|p| p.display().to_string()),
            validation: &validation,
        })?;
    } else {
        print_validation(&args, &task, &validation);
    }
    match validation.verdict {
        Verdict::Passes => Ok(()),
        v => Err(CliError::internal(format!(
            "{}: {}",
            args.spec.display(),
            v.label()
        ))),
    }
}

/// `passed/run`.
fn passed_of(o: &Outcome) -> String {
    format!("{}/{}", o.passed, o.run)
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
    let essential = if a.essential { "yes" } else { "NO" };
    vec![a.what.clone(), trials, essential.into(), why]
}

fn print_answers(demo: &Path, answers: &Answers) {
    println!(
        "answers of {} (the spec AKL learns from it {} the spec validated; it has {} line(s) and passed {}):",
        demo.display(),
        if answers.spec_is_learned_from_demo {
            "is"
        } else {
            "is not"
        },
        answers.lines,
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
        "passed then",
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
            AnswerVerdict::Inconclusive => "inconclusive: the flip does not fix most failures",
            AnswerVerdict::Unchanged => "unchanged: the flip learns the same spec",
        };
        table.row(vec![
            format!("  {}", c.index),
            format!("{:.2}", c.t),
            format!("{:?}", c.answer).to_lowercase(),
            format!("{:?}", c.flipped_to).to_lowercase(),
            c.lines_when_flipped.to_string(),
            c.outcome.as_ref().map_or("-".into(), passed_of),
            verdict.into(),
        ]);
    }
    print!("{}", table.render());
}

fn print_validation(args: &ValidateArgs, task: &Task, v: &Validation) {
    let n = v.trials.count;
    println!(
        "{} on task `{}`: {} randomized trials (seeds {}..{}), goals drawn across every TSR",
        args.spec.display(),
        task.name,
        n,
        v.trials.seed,
        v.trials.seed + n as u64 - 1
    );
    let o = &v.outcome;
    let causes: Vec<String> = o.failures.iter().map(|(c, k)| format!("{c} {k}")).collect();
    println!(
        "spec: passed {}{}",
        passed_of(o),
        if causes.is_empty() {
            String::new()
        } else {
            format!(" (failed: {})", causes.join(", "))
        }
    );
    if let Some(f) = o.first_failure_text() {
        println!("  first failure: {f}");
    }
    let seeds = if o.passed == 0 {
        "on every seed (the spec passed none)"
    } else {
        "on the seeds the spec passed"
    };
    println!(
        "without each keyframe and each line, {seeds}, each run stopped at its first failure:"
    );
    let mut table = Table::new(["  removed", "passed", "essential", "first failure"]);
    for a in &v.removals {
        let mut row = removal_row(a);
        row[0] = format!("  {}", row[0]);
        table.row(row);
    }
    print!("{}", table.render());
    if let (Some(answers), Some(demo)) = (&v.answers, &args.demo) {
        print_answers(demo, answers);
    }
    let superfluous: Vec<&str> = v.not_essential().map(|a| a.what.as_str()).collect();
    let mut reasons = Vec::new();
    if !superfluous.is_empty() {
        reasons.push(format!(
            "not essential: {} (the spec passes every trial without it)",
            superfluous.join(", ")
        ));
    }
    let contradicted = v.contradicted().count();
    if contradicted > 0 {
        reasons.push(format!("{contradicted} answer(s) contradicted"));
    }
    println!(
        "verdict: {}{}",
        v.verdict.label(),
        if reasons.is_empty() {
            String::new()
        } else {
            format!(" — {}", reasons.join("; "))
        }
    );
}
