//! `akl compare SPEC... --task T`: one row per spec.

use super::execute::jobs;
use super::robot::load as load_robot;
use super::validate::{cli_error, exec_options, gate_options};
use super::{load_spec_for, print_json};
use crate::cli::CompareArgs;
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_stats::percent;
use akl_stats::GateOptions;
use akl_validate::compare::{compare, CompareOptions, Row};
use akl_validate::ValidateOptions;
use serde::Serialize;

#[derive(Serialize)]
struct Compared {
    task: String,
    gate: GateOptions,
    scenes: usize,
    budget_ms: u64,
    seed: u64,
    speed_scale: f64,
    interrupted: bool,
    rows: Vec<Row>,
}

pub(super) fn run(args: CompareArgs) -> CliResult {
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let specs = args
        .specs
        .iter()
        .map(|p| Ok((p.display().to_string(), load_spec_for(p, &task, args.fit)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    let options = CompareOptions {
        validate: ValidateOptions {
            seed: args.seed,
            jobs: jobs(args.trials.jobs)?,
            gate: gate_options(&args.gate, GateOptions::default().max_trials)?,
            exec: exec_options(&args.trials),
        },
        scenes: args.scenes,
        budget_ms: args.budget,
    };
    let progress = Progress::new(&format!("comparing on `{}`", task.name), specs.len());
    let rows = compare(&robot, &task, &specs, &options, &|done, _| {
        progress.set(done)
    });
    progress.finish();
    // Every spec was loaded and checked against the task above, so an error here is the
    // task's or the run's, not a file's; clap guarantees at least one spec to name.
    let comparison = rows.map_err(|e| cli_error(e, &args.specs[0], &task))?;
    let compared = Compared {
        task: task.name.clone(),
        gate: options.validate.gate,
        scenes: args.scenes,
        budget_ms: args.budget,
        seed: args.seed,
        speed_scale: args.trials.speed.speed_scale,
        interrupted: comparison.interrupted,
        rows: comparison.rows,
    };
    if args.json {
        print_json(&compared)?;
    } else {
        print_compared(&compared);
    }
    if compared.interrupted {
        return Err(CliError::interrupted(format!(
            "interrupted: {} of {} specs compared, the last possibly on fewer trials",
            compared.rows.len(),
            specs.len()
        )));
    }
    Ok(())
}

fn print_compared(c: &Compared) {
    println!(
        "task `{}`: bits of freedom on the 5 cm lattice; planning over {} randomized scenes (budget {} ms); validation by the gate (success {} at {:.0} % confidence, at most {} trials from seed {}); pass rates with their 95 % interval",
        c.task, c.scenes, c.budget_ms, c.gate.min_success, 100.0 * c.gate.confidence, c.gate.max_trials, c.seed
    );
    if c.interrupted {
        println!("interrupted: only the specs compared are listed");
    }
    let mut table = Table::new([
        "spec",
        "method",
        "keyframes",
        "constraints",
        "bits",
        "plan success",
        "best duration",
        "pass rate",
        "validation",
    ]);
    for r in &c.rows {
        let verdict = match r.verdict {
            None => format!("interrupted after {} trials", r.trials),
            Some(v) if r.not_essential.is_empty() => v.label().to_string(),
            Some(v) => format!(
                "{} (not essential: {})",
                v.label(),
                r.not_essential.join(", ")
            ),
        };
        table.row(vec![
            r.spec.clone(),
            r.method.clone(),
            r.keyframes.to_string(),
            r.constraints.to_string(),
            r.bits.map_or("no trace".into(), |b| format!("{b:.1}")),
            format!("{:.0} %", r.plan_success * 100.0),
            r.best_duration.map_or("-".into(), |d| format!("{d:.2} s")),
            format!(
                "{}/{} ({}–{})",
                r.pass_rate.passed,
                r.pass_rate.trials,
                percent(r.pass_rate.lower),
                percent(r.pass_rate.upper)
            ),
            verdict,
        ]);
    }
    print!("{}", table.render());
}
