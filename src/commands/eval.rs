//! `akl eval`: the simulated study.

use super::print_json;
use super::robot::load as load_robot;
use crate::cli::{EvalArgs, RobotArg};
use crate::exit::{CliError, CliResult};
use crate::table::{seconds, Table};
use akl_eval::{
    merge_studies, method_label, read_study, run_study, summarize, write_records, Executor, Study,
    StudyOptions, Summary, Trial, TABLE_ORDER, THESIS_CONSTRAINT_ERRORS, THESIS_SUCCESS,
};
use akl_exec::batch::{Batch, BatchOptions};
use akl_exec::ExecOptions;
use akl_planner::Robot;
use akl_scene::{builtin, Task};
use akl_tsr::TaskSpec;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::PathBuf;

/// Executes learned specs through the execution engine's batch API: the one place the study
/// meets the robot and the simulation.
struct Simulation {
    robot: Robot,
}

impl Executor for Simulation {
    fn passes(
        &self,
        spec: &TaskSpec,
        task: &Task,
        trials: usize,
        seed: u64,
    ) -> Result<usize, String> {
        let exec = ExecOptions::default();
        let options = BatchOptions {
            trials,
            randomize: true,
            seed,
            jobs: 1,
        };
        let batch =
            Batch::new(&self.robot, task, spec, &exec, options).map_err(|e| e.to_string())?;
        let report = batch.run(&|_| {}).map_err(|e| e.to_string())?;
        Ok(report.passed)
    }
}

/// What `--json` prints.
#[derive(Serialize)]
struct Evaluated<'a> {
    participants: usize,
    seed: u64,
    interrupted: bool,
    executions_per_spec: Option<usize>,
    wall_s: f64,
    files: Vec<String>,
    summary: &'a Summary,
    trials: Vec<&'a Trial>,
}

pub(super) fn run(args: EvalArgs) -> CliResult {
    if !args.merge.is_empty() {
        return merge(&args);
    }
    if args.participants == 0 {
        return Err(CliError::input("--participants: needs at least one"));
    }
    if args.execute == Some(0) {
        return Err(CliError::input(
            "--execute: needs at least one run per spec",
        ));
    }
    if let Some(dir) = &args.out {
        prepare_folder(dir)?;
    }
    let only = match args.shard {
        Some(request) => {
            let shard = request
                .resolve(|name| std::env::var(name).ok())
                .map_err(CliError::input)?;
            Some(
                shard
                    .nonempty_trials(args.participants)
                    .map_err(|e| CliError::input(format!("--shard: {e}")))?,
            )
        }
        None => None,
    };
    let tasks: Vec<Task> = builtin::study_names()
        .into_iter()
        .map(builtin::resolve)
        .collect::<Result<_, _>>()
        .map_err(CliError::internal)?;
    let names: Vec<String> = tasks.iter().map(|t| t.name.clone()).collect();
    let simulation = match args.execute {
        Some(_) => Some(Simulation {
            robot: load_robot(&RobotArg {
                robot: None,
                package_path: Vec::new(),
            })?,
        }),
        None => None,
    };
    let options = StudyOptions {
        participants: args.participants,
        seed: args.seed,
        tasks: &tasks,
        execute: simulation
            .as_ref()
            .zip(args.execute)
            .map(|(s, n)| (s as &dyn Executor, n)),
        only: only.clone(),
        stop: Some(crate::stop::on_ctrl_c()),
    };
    let total = only.as_ref().map_or(args.participants, |b| b.len()) * 3 * tasks.len();
    let bar = ProgressBar::new(total as u64).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} trials, {elapsed} ({eta} left)")
            .map_err(CliError::internal)?
            .progress_chars("#>-"),
    );
    bar.set_message("simulated study");
    let started = std::time::Instant::now();
    let study = run_study(&options, &|_| bar.inc(1));
    bar.finish_and_clear();
    let study = study.map_err(CliError::internal)?;
    let wall_s = started.elapsed().as_secs_f64();
    report(&args, &study, &names, wall_s)?;
    if study.interrupted {
        return Err(CliError::interrupted(format!(
            "interrupted: {} of {total} trials finished",
            study.trials.len()
        )));
    }
    Ok(())
}

/// `akl eval --merge PARTS...`: the shards of a study joined, and reported as a study.
fn merge(args: &EvalArgs) -> CliResult {
    if let Some(dir) = &args.out {
        prepare_folder(dir)?;
    }
    let parts = args
        .merge
        .iter()
        .map(|p| read_study(p).map(|s| (p.clone(), s)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(CliError::input)?;
    let study = merge_studies(&parts).map_err(CliError::input)?;
    let names: Vec<String> = builtin::study_names()
        .into_iter()
        .map(str::to_string)
        .collect();
    report(args, &study, &names, 0.0)
}

/// Writes the records of `study` (with --out) and prints its tables (or, with --json, the
/// study).
fn report(args: &EvalArgs, study: &Study, names: &[String], wall_s: f64) -> CliResult {
    let summary = summarize(&study.trials, names);
    let files = match &args.out {
        Some(dir) => write_records(dir, study, &summary, names)
            .map_err(CliError::internal)?
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        None => Vec::new(),
    };
    if args.json {
        print_json(&Evaluated {
            participants: study.participants.len(),
            seed: study.seed,
            interrupted: study.interrupted,
            executions_per_spec: study.executions_per_spec,
            wall_s,
            files,
            summary: &summary,
            trials: study.trials.iter().collect(),
        })?;
    } else {
        print_study(study, &summary, wall_s);
        for f in &files {
            println!("wrote {f}");
        }
    }
    Ok(())
}

/// Creates the output folder if missing; a file in its place is bad input.
fn prepare_folder(dir: &PathBuf) -> Result<(), CliError> {
    if dir.exists() && !dir.is_dir() {
        return Err(CliError::input(format!(
            "{}: is a file; --out needs a folder",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::input(format!("{}: cannot create the folder: {e}", dir.display())))
}

fn percent(x: f64) -> String {
    format!("{x:.1}")
}

/// Prints the tables: success (Table 4.1), constraint errors (Table 4.2), runtime, passes.
fn print_study(study: &Study, summary: &Summary, wall_s: f64) {
    let experienced = study.participants.iter().filter(|p| p.experienced).count();
    println!(
        "simulated study: {} participants ({experienced} experienced with robots), seed {}, {} trials in {wall_s:.1} s",
        study.participants.len(),
        study.seed,
        study.trials.len()
    );
    if study.interrupted {
        println!("interrupted: only the trials that finished are counted");
    }
    println!("\nsuccess rate, % (cf. thesis Table 4.1, case (a); thesis values in brackets)");
    let mut t = Table::new(["task", "KD", "mACL", "AKL"]);
    for row in &summary.success {
        let thesis = THESIS_SUCCESS.iter().find(|(n, _)| *n == row.task);
        let mut cells = vec![row.task.clone()];
        for (i, m) in TABLE_ORDER.iter().enumerate() {
            let r = row.rate(*m);
            let reference = thesis.map_or(String::new(), |(_, v)| format!(" ({})", percent(v[i])));
            cells.push(format!(
                "{} ({}/{}){reference}",
                percent(r.percent),
                r.successes,
                r.trials
            ));
        }
        t.row(cells);
    }
    print!("{}", t.render());
    let c = &summary.constraint_errors;
    let th = &THESIS_CONSTRAINT_ERRORS;
    println!("\nconstraint errors (cf. thesis Table 4.2)");
    let mut t = Table::new(["", "simulated", "thesis"]);
    for (what, sim, thesis) in [
        ("AKL: constraint errors", c.akl_errors, th.akl_errors),
        (
            "AKL: due to answers",
            c.akl_errors_from_answers,
            th.akl_errors_from_answers,
        ),
        (
            "AKL: avoided by answers",
            c.akl_errors_avoided,
            th.akl_errors_avoided,
        ),
        ("mACL: constraint errors", c.macl_errors, th.macl_errors),
    ] {
        t.row(vec![what.into(), sim.to_string(), thesis.to_string()]);
    }
    print!("{}", t.render());
    println!("\nlearning runtime per trial (cf. thesis §4.6.8: AKL 0.011 s, KD 0.001 s, mACL 2.64 s mean)");
    let mut t = Table::new(["method", "mean", "median", "max"]);
    for r in &summary.runtime {
        t.row(vec![
            method_label(r.method).into(),
            seconds(r.mean_s),
            seconds(r.median_s),
            seconds(r.max_s),
        ]);
    }
    print!("{}", t.render());
    if let Some(rows) = &summary.pass_rates {
        println!("\npass rate in simulation: executions passed, every spec's pooled (95 % CI)");
        let mut t = Table::new(["task", "KD", "mACL", "AKL"]);
        for row in rows {
            let mut cells = vec![row.task.clone()];
            cells.extend(
                row.pass_rate
                    .iter()
                    .map(|r| r.map_or("-".into(), |r| r.to_string())),
            );
            t.row(cells);
        }
        print!("{}", t.render());
    }
}
